"""A streaming client written with unmodified pyads: start the streaming program on channel 1,
stream an NC file in whole-line packets of at most 992 bytes, retry on 0x708 (the channel's
11012), wait until the program has ended, print one JSON line of counts.

    NCCHANNEL_ADS_ADDR=127.0.0.1:48898 python tests/python/stream_with_pyads.py FILE
"""

import ctypes
import json
import os
import sys
import time

import pyads

from checks import delete_notification

ADDR = os.environ["NCCHANNEL_ADS_ADDR"]
NETID = os.environ.get("NCCHANNEL_ADS_NETID", "127.0.0.1.1.1")
GROUP = 0x20101
OFF_STREAM, OFF_MODE_STATE, OFF_MODE, OFF_STATE, OFF_PROGRAM = 0x90, 0x103, 0x104, 0x105, 0x108
DINT2 = ctypes.c_int32 * 2


def packets(path):
    cur = b""
    with open(path, "rb") as f:
        for line in f:
            line = line.rstrip(b"\r\n") + b"\r\n"
            if len(cur) + len(line) > 992:
                yield cur
                cur = b""
            cur += line
    if cur:
        yield cur


def main():
    pyads.open_port()
    pyads.set_local_address("10.1.2.3.1.1")
    plc = pyads.Connection(NETID, 553, ADDR)
    plc.open()
    notes = []

    @plc.notification(DINT2)
    def on_mode_state(handle, name, timestamp, value):
        notes.append(list(value))

    attr = pyads.NotificationAttrib(8, trans_mode=pyads.constants.ADSTRANS_SERVERONCHA)
    handle = plc.add_device_notification((GROUP, OFF_MODE_STATE), attr, on_mode_state)
    plc.write(GROUP, OFF_MODE, 2, pyads.PLCTYPE_DINT)
    name = b"streaming.nc\0"
    plc.write(GROUP, OFF_PROGRAM, list(name), ctypes.c_uint8 * len(name))
    plc.write(GROUP, OFF_STATE, 4, pyads.PLCTYPE_DINT)
    busy = writes = 0
    for p in packets(sys.argv[1]):
        while True:
            try:
                plc.write(GROUP, OFF_STREAM, list(p), ctypes.c_uint8 * len(p))
                writes += 1
                break
            except pyads.ADSError as e:
                if e.err_code != 0x708:
                    raise
                busy += 1
                time.sleep(0.001)
    deadline = time.time() + 120
    while True:
        mode, state = plc.read(GROUP, OFF_MODE_STATE, DINT2)
        if state == 3:
            break
        if time.time() > deadline:
            raise SystemExit("program did not end")
        time.sleep(0.005)
    time.sleep(0.05)
    delete_notification(plc, handle)
    plc.close()
    pyads.close_port()
    print(json.dumps({"writes": writes, "busy": busy, "notifications": notes}))


if __name__ == "__main__":
    main()
