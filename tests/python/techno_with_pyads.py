"""Unmodified pyads as the PLC of a channel's technology units (port 851): M25 is MVS_SVS in
the channel's table, program `techno.nc` is `N10 G01 X10 F6000 / N20 X20 M25 / N30 X30 / M30`.

    NCCHANNEL_ADS_ADDR=127.0.0.1:48898 python tests/python/techno_with_pyads.py

The PLC sets head.plc_present_w, starts the program through the mode-and-state command unit,
subscribes to techno_unit_std_sync by name (on change, as kimblad/TwinSharp
TwinSharp/CNC/TechnologyProcesses.cs does), reads used_units_std_sync_r and the unit by name
when a sample shows a unit asking, holds the acknowledgement for 200 ms, then writes
please_rw FALSE and done_w TRUE (TF5200 HLI "Technology functions"; the unit's data as
"Data of the M/H function"). Prints one JSON line with what it saw; exits non-zero on a
failed check.
"""

import ctypes
import json
import os
import struct
import threading
import time

import pyads

from checks import check, delete_notification, wait_for

ADDR = os.environ["NCCHANNEL_ADS_ADDR"]
NETID = os.environ.get("NCCHANNEL_ADS_NETID", "127.0.0.1.1.1")
P = "HLI_Global_Variables.gpCh[0]^"
MS = P + ".channel_mc_control.mode_and_state"
UNIT = 47
UNITS = ctypes.c_uint8 * (20 * UNIT)
ONE_UNIT = ctypes.c_uint8 * UNIT
TRANSITION = ctypes.c_uint8 * 327


def start(plc, program):
    """The command unit: command_w (to mode AUTOMATIC, to state ACTIVE, the program), then
    command_semaphor_rw TRUE."""
    b = bytearray(327)
    struct.pack_into("<5I", b, 0, 0, 0, 2, 4, 0)
    b[24:24 + len(program)] = program
    plc.write_by_name(MS + ".command_w", list(b), TRANSITION)
    plc.write_by_name(MS + ".command_semaphor_rw", True, pyads.PLCTYPE_BOOL)


def decode(u):
    """TECHNO_UNIT_CH: please_rw, done_w, type, fill, then HLI_M_H_PROZESS at 8."""
    u = bytes(u)
    nr, time_us, block_nr, prg_line, add_value, _late, _fill, synch_mode = struct.unpack_from(
        "<IiIIiHHI", u, 8)
    return {
        "please": u[0], "done": u[1], "type": struct.unpack_from("<H", u, 2)[0], "nr": nr,
        "time": time_us, "block_nr": block_nr, "prg_line": prg_line, "add_value": add_value,
        "synch_mode": synch_mode,
    }


def main():
    pyads.open_port()
    pyads.set_local_address("10.1.2.3.1.1")
    plc = pyads.Connection(NETID, 851, ADDR)
    plc.open()
    seen = {}

    plc.write_by_name(P + ".head.plc_present_w", True, pyads.PLCTYPE_BOOL)
    check(plc.read_by_name(P + ".head.plc_present_w", pyads.PLCTYPE_BOOL) is True, "plc_present_w")
    check(plc.read_by_name(P + ".used_units_std_sync_r", pyads.PLCTYPE_UINT) == 0, "nothing to do yet")

    lock = threading.Lock()
    asking = []

    def on_change(notification, _name):
        _h, _ts, value = plc.parse_notification(notification, UNITS)
        with lock:
            if bytes(value)[0] == 1:
                asking.append(decode(bytes(value)[:UNIT]))

    attr = pyads.NotificationAttrib(ctypes.sizeof(UNITS), trans_mode=pyads.ADSTRANS_SERVERONCHA,
                                    cycle_time=25)
    handles = plc.add_device_notification(P + ".techno_unit_std_sync", attr, on_change)

    start(plc, b"techno.nc")
    wait_for("a notification with a unit asking", lambda: len(asking) > 0)
    used = plc.read_by_name(P + ".used_units_std_sync_r", pyads.PLCTYPE_UINT)
    check(used == 1, "one unit to acknowledge, got %r" % used)
    with lock:
        seen["notified"] = asking[0]
    unit = decode(plc.read_by_name(P + ".techno_unit_std_sync[0]", ONE_UNIT))
    seen["unit"] = unit
    check(plc.read_by_name(P + ".techno_unit_std_sync[0].type", pyads.PLCTYPE_UINT) == 1, "type M")
    try:
        plc.write_by_name(P + ".used_units_std_sync_r", 0, pyads.PLCTYPE_UINT)
        check(False, "used_units_std_sync_r is read-only")
    except pyads.ADSError as e:
        check(e.err_code == 0x704, "read-only: 0x704, got %r" % e)

    # Hold the acknowledgement: the channel waits for it (MVS_SVS).
    time.sleep(0.2)
    state = plc.read_by_name(MS + ".state_r.state", pyads.PLCTYPE_UDINT)
    check(state == 4, "still ACTIVE while the M waits, got %r" % state)
    plc.write_by_name(P + ".techno_unit_std_sync[0].please_rw", False, pyads.PLCTYPE_BOOL)
    check(plc.read_by_name(P + ".techno_unit_std_sync[0].please_rw", pyads.PLCTYPE_BOOL) is False,
          "fetched")
    plc.write_by_name(P + ".techno_unit_std_sync[0].done_w", True, pyads.PLCTYPE_BOOL)
    wait_for("program end", lambda: plc.read_by_name(MS + ".state_r.state", pyads.PLCTYPE_UDINT) == 3)
    seen["used_after"] = plc.read_by_name(P + ".used_units_std_sync_r", pyads.PLCTYPE_UINT)
    delete_notification(plc, handles)
    plc.close()
    print(json.dumps(seen))


if __name__ == "__main__":
    main()
