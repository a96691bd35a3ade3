"""ADS state control, member paths and refusals seen by unmodified pyads against the real
channels.

    NCCHANNEL_ADS_ADDR=127.0.0.1:48898 python tests/python/control_with_pyads.py

Channel 1 must be AUTOMATIC/READY with streaming program `streaming.nc` configured. Prints
one JSON line with what it saw; exits non-zero on a failed check.

write_control / read_state on 851 (PLC runtime STOP, RUN, RESET), 553 (RESET: every channel
reset) and 10000 (CONFIG as `adstool … state 15`, then RESET: restart); levels of the HLI's
type tree by handle and symbol info (`get_handle`, `get_symbol`, `read_by_name`); a start
while the channel is in ERROR answered 0x707 (not 0x708: retrying cannot help).
"""

import json
import os

import pyads

from checks import check, open_connections

ADDR = os.environ["NCCHANNEL_ADS_ADDR"]
NETID = os.environ.get("NCCHANNEL_ADS_NETID", "127.0.0.1.1.1")
P = "HLI_Global_Variables.gpCh[0]^"
MS = P + ".channel_mc_control.mode_and_state"
RESET, RUN, STOP, CONFIG = 2, 5, 6, 15
CH = 0x120101
MODE, STATE, PROGRAM, STREAM = 0x104, 0x105, 0x108, 0x90
ACTIVE_STATE = 0x109


def ads_error(call):
    """The ADS error code `call` raises (None when it succeeds)."""
    try:
        call()
    except pyads.ADSError as e:
        return e.err_code
    return None


def start_streaming(com):
    com.write(CH, MODE, 2, pyads.PLCTYPE_DINT)
    com.write(CH, PROGRAM, "streaming.nc", pyads.PLCTYPE_STRING)
    com.write(CH, STATE, 4, pyads.PLCTYPE_DINT)
    check(com.read(CH, ACTIVE_STATE, pyads.PLCTYPE_DINT) == 4, "ACTIVE")


def main():
    system, plc, com = open_connections(NETID, ADDR)
    seen = {}

    # Levels of the type tree: inside a root, above the roots.
    kopf = plc.get_symbol(P + ".mc_error.satz_r.kopf")
    seen["kopf"] = [kopf.symbol_type, len(plc.read_by_name(kopf.name, pyads.PLCTYPE_BYTE * 104))]
    unit = plc.get_symbol(MS)
    seen["mode_and_state"] = [unit.symbol_type, len(unit.read())]
    state = plc.read_by_name(MS, pyads.PLCTYPE_BYTE * 8)
    seen["mode_and_state_head"] = list(state)
    for name in (P, "HLI_Global_Variables"):
        h = plc.get_handle(name)
        check(h > 0, name + " has a handle")
        plc.release_handle(h)
    seen["gpCh_pointer"] = ads_error(lambda: plc.get_handle("HLI_Global_Variables.gpCh"))
    seen["write_mode_and_state"] = ads_error(
        lambda: plc.write_by_name(MS, [0] * 8, pyads.PLCTYPE_BYTE * 8))

    # PLC runtime: STOP, RUN, RESET (variables initial, then STOP).
    plc.write_by_name(MS + ".enable_w", True, pyads.PLCTYPE_BOOL)
    states = []
    for s in (STOP, RUN, RESET):
        plc.write_control(s, 0, 0, pyads.PLCTYPE_INT)
        states.append(plc.read_state()[0])
    seen["plc_states"] = states
    seen["enable_after_reset"] = plc.read_by_name(MS + ".enable_w", pyads.PLCTYPE_BOOL)
    plc.write_control(RUN, 0, 0, pyads.PLCTYPE_INT)

    # A start in ERROR: 0x707.
    start_streaming(com)
    seen["no_line_end"] = ads_error(lambda: com.write(CH, STREAM, "N10 X1\n", pyads.PLCTYPE_STRING))
    check(com.read(CH, ACTIVE_STATE, pyads.PLCTYPE_DINT) == 6, "ERROR")
    seen["start_in_error"] = ads_error(lambda: com.write(CH, STATE, 4, pyads.PLCTYPE_DINT))

    # CNC task: RESET resets the channel, the task runs on.
    com.write_control(RESET, 0, 0, pyads.PLCTYPE_INT)
    seen["after_cnc_reset"] = [com.read(CH, ACTIVE_STATE, pyads.PLCTYPE_DINT), com.read_state()[0]]

    # System service: CONFIG, the runtime gone; RESET restarts it.
    start_streaming(com)
    system.write_control(CONFIG, 0, 0, pyads.PLCTYPE_INT)
    seen["system_config"] = system.read_state()[0]
    seen["plc_in_config"] = ads_error(plc.read_state)
    system.write_control(RESET, 0, 0, pyads.PLCTYPE_INT)
    seen["after_restart"] = [system.read_state()[0], plc.read_state()[0],
                             com.read(CH, ACTIVE_STATE, pyads.PLCTYPE_DINT)]
    for c in (system, plc, com):
        c.close()
    print(json.dumps(seen))


if __name__ == "__main__":
    main()
