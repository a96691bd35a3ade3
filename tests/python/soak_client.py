"""An external streaming client for `ncchannel serve --soak`, written with unmodified pyads:
writes numbered, self-contained NC lines (every move carries its feed, so a line after an
injected reset runs on its own) into channel 1's stream for SECONDS, retrying on 0x708 as
every client must, and ignoring 0x707 while the server resets the channel. The server starts
the streaming program and restarts it after each reset. It watches mode and state with an
on-change notification sampled every 50 ms and counts the times it saw the channel READY
(each injected reset holds READY for 250 ms). With --duplicate it writes one acknowledged
packet a second time on purpose (the exactly-once check must catch it).
Prints one JSON line of counts.

    NCCHANNEL_ADS_ADDR=127.0.0.1:48898 python tests/python/soak_client.py SECONDS [--duplicate]
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
OFF_STREAM, OFF_MODE_STATE = 0x90, 0x103
BUSY, NOT_READY = 0x708, 0x707
READY = 3
DINT2 = ctypes.c_int32 * 2


def lines():
    n = 1
    while True:
        if n % 4 == 0:
            x, y = (n % 40) * 0.05, (n % 17) * 0.05
            yield f"N{n} G01 X{x:.3f} Y{y:.3f} F20000\r\n".encode()
        else:
            yield f"N{n} P{1 + n % 9}={n}\r\n".encode()
        n += 1


def write_again(plc, p, end):
    """Write packet `p` a second time, retrying while the buffer is full (BUSY): a full
    buffer at that moment must not turn the duplicate into a plain retry the flag misses."""
    while time.monotonic() < end:
        try:
            plc.write(GROUP, OFF_STREAM, list(p), ctypes.c_uint8 * len(p))
            return True
        except pyads.ADSError as e:
            if e.err_code != BUSY:
                raise
            time.sleep(0.002)
    return False


def main():
    seconds = float(sys.argv[1])
    duplicate = "--duplicate" in sys.argv
    pyads.open_port()
    pyads.set_local_address("10.1.2.3.1.1")
    plc = pyads.Connection(NETID, 553, ADDR)
    plc.open()
    states = []

    @plc.notification(DINT2)
    def on_mode_state(handle, name, timestamp, value):
        states.append(value[1])

    # pyads takes the cycle time in ms; 50 ms is well inside the 250 ms READY hold.
    attr = pyads.NotificationAttrib(8, trans_mode=pyads.constants.ADSTRANS_SERVERONCHA,
                                    cycle_time=50)
    handle = plc.add_device_notification((GROUP, OFF_MODE_STATE), attr, on_mode_state)
    gen = lines()
    end = time.monotonic() + seconds
    busy = refused = writes = line_count = 0
    duplicated = False
    while time.monotonic() < end:
        p = b""
        while len(p) < 600:
            p += next(gen)
        while time.monotonic() < end:
            try:
                plc.write(GROUP, OFF_STREAM, list(p), ctypes.c_uint8 * len(p))
                writes += 1
                line_count += p.count(b"\n")
                if duplicate and not duplicated and writes == 20:
                    duplicated = write_again(plc, p, end)
                break
            except pyads.ADSError as e:
                if e.err_code == BUSY:
                    busy += 1
                    time.sleep(0.002)
                elif e.err_code == NOT_READY:
                    refused += 1
                    time.sleep(0.01)
                else:
                    raise
    delete_notification(plc, handle)
    plc.close()
    # Times the channel was seen entering READY (the first sample counts when it is READY).
    ready_seen = sum(1 for i, st in enumerate(states)
                     if st == READY and (i == 0 or states[i - 1] != READY))
    print(json.dumps({"writes": writes, "lines": line_count, "busy": busy,
                      "not_ready": refused, "duplicated": duplicated,
                      "ready_seen": ready_seen, "states": len(states)}))


if __name__ == "__main__":
    main()
