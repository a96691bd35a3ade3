"""The PLC runtime's symbol services and ADS sum commands (port 851) and the TwinCAT system
service (port 10000) seen by unmodified pyads against the real channels.

    NCCHANNEL_ADS_ADDR=127.0.0.1:48898 python tests/python/symbols_with_pyads.py

Channel 1 must be AUTOMATIC/READY with streaming program `streaming.nc` configured. Prints
one JSON line with what it saw; exits non-zero on a failed check.

read_state() on 10000 as `adstool <netid> state` does; get_all_symbols (upload info 0xF00F,
symbol upload 0xF00B); read_list_by_name / write_list_by_name (symbol info 0xF009, sum read
0xF080, sum write 0xF081): one sum write hands the mode-and-state command unit to the CNC in
order (command fields first, the semaphore last), and the started program is read back
through a handle and on the COM task.
"""

import json
import os

import pyads

from checks import check, open_connections, wait_for

ADDR = os.environ["NCCHANNEL_ADS_ADDR"]
NETID = os.environ.get("NCCHANNEL_ADS_NETID", "127.0.0.1.1.1")
MS = "HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state"
AUTOMATIC, READY, ACTIVE, RESETTING = 2, 3, 4, 15
ADS_STATE_RUN = 5
GROUP_VALUE_BY_HANDLE = 0xF005
CH = 0x120101
MCM_ACTIVE_STATE = 0x109


def main():
    system, plc, com = open_connections(NETID, ADDR)
    seen = {}

    seen["system_state"] = list(system.read_state())
    check(seen["system_state"][0] == ADS_STATE_RUN, "system service in RUN")
    name, _version = system.read_device_info()
    seen["system_device"] = name
    check(plc.read_state()[0] == ADS_STATE_RUN, "PLC runtime in RUN")

    symbols = plc.get_all_symbols()
    by_name = {s.name: s for s in symbols}
    check(MS + ".state_r" in by_name, "state_r uploaded")
    check(by_name[MS + ".state_r"].symbol_type == "HLI_IMCM_MODE_STATE", "state_r type")
    check(all(s.index_group == GROUP_VALUE_BY_HANDLE for s in symbols), "value-by-handle addresses")
    seen["symbols"] = len(symbols)

    names = [MS + ".state_r.mode", MS + ".state_r.state", MS + ".enable_w", MS + ".command_w.parameter"]
    before = plc.read_list_by_name(names)
    check(before[MS + ".state_r.mode"] == AUTOMATIC, "mode read by sum: %r" % before)
    check(before[MS + ".state_r.state"] == READY, "state read by sum: %r" % before)
    check(before[MS + ".enable_w"] is False, "enable_w read by sum")

    # One sum write, applied in order: the command, then the semaphore hands it over.
    results = plc.write_list_by_name({
        MS + ".command_w.to_mode": AUTOMATIC,
        MS + ".command_w.to_state": ACTIVE,
        MS + ".command_w.parameter": "streaming.nc",
        MS + ".command_semaphor_rw": True,
    })
    check(all(r == "no error" for r in results.values()), "sum write results: %r" % results)
    seen["write_results"] = sorted(set(results.values()))

    handle = plc.get_handle(MS + ".state_r.state")
    by_handle = wait_for(
        "ACTIVE by handle",
        lambda: plc.read_by_name("", pyads.PLCTYPE_UDINT, handle=handle) == ACTIVE,
    )
    plc.release_handle(handle)
    check(by_handle, "ACTIVE read through a handle")
    check(com.read(CH, MCM_ACTIVE_STATE, pyads.PLCTYPE_DINT) == ACTIVE, "COM shows ACTIVE")
    after = plc.read_list_by_name(names)
    check(after[MS + ".command_w.parameter"] == "streaming.nc", "parameter read back: %r" % after)
    check(after[MS + ".state_r.state"] == ACTIVE, "state by sum read")
    seen["state_after"] = after[MS + ".state_r.state"]

    plc.write_list_by_name({
        MS + ".command_w.to_mode": 0,
        MS + ".command_w.to_state": RESETTING,
        MS + ".command_w.parameter": "",
        MS + ".command_semaphor_rw": True,
    })
    wait_for("READY after the reset", lambda: plc.read_by_name(MS + ".state_r.state") == READY)
    for c in (system, plc, com):
        c.close()
    print(json.dumps(seen))


if __name__ == "__main__":
    main()
