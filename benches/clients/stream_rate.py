"""Stream-interface throughput seen by unmodified pyads: one sequential client streams
17-byte parameter lines (`N12345 P1=12345`, as `ncchannel bench --load ads-stream`) into
channel 1 of a running `ncchannel serve`, packets of 58 lines (986 bytes), a write answered
0x708 (buffer full) sent again at once, for SECONDS after a 0.5 s warm-up. Prints one JSON
line: bytes/s and the share of the interface's 4094 bytes per 1 ms cycle.

    NCCHANNEL_ADS_ADDR=127.0.0.1:48898 python benches/clients/stream_rate.py [SECONDS]
"""

import ctypes
import json
import os
import sys
import time

import pyads

ADDR = os.environ.get("NCCHANNEL_ADS_ADDR", "127.0.0.1:48898")
NETID = os.environ.get("NCCHANNEL_ADS_NETID", "127.0.0.2.1.1")
GROUP = 0x20101
OFF_STREAM, OFF_MODE, OFF_STATE, OFF_PROGRAM, OFF_RESET = 0x90, 0x104, 0x105, 0x108, 0x13C
BUSY = 0x708
NOMINAL = 4094 / 0.001  # bytes/s: one full stream buffer per 1 ms cycle
LINES_PER_PACKET = 992 // 17


def packets():
    k = 0
    while True:
        p = b""
        for _ in range(LINES_PER_PACKET):
            n = 10000 + k % 90000
            p += b"N%d P1=%d\r\n" % (n, n)
            k += 1
        yield p


def main():
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 5.0
    pyads.open_port()
    pyads.set_local_address("10.1.2.3.1.1")
    plc = pyads.Connection(NETID, 553, ADDR)
    plc.open()

    def write(offset, value, kind):
        """A write answered busy (0x708) is sent again; anything else fails the run."""
        while True:
            try:
                return plc.write(GROUP, offset, value, kind)
            except pyads.ADSError as e:
                if e.err_code != BUSY:
                    raise

    # A reset first: an earlier run may have left the streaming program running.
    write(OFF_RESET, 1, pyads.PLCTYPE_DINT)
    write(OFF_MODE, 2, pyads.PLCTYPE_DINT)
    name = b"streaming.nc\0"
    write(OFF_PROGRAM, list(name), ctypes.c_uint8 * len(name))
    write(OFF_STATE, 4, pyads.PLCTYPE_DINT)
    kind = ctypes.c_uint8 * (LINES_PER_PACKET * 17)
    start = time.perf_counter()
    t0 = None
    sent = busy = 0
    for p in packets():
        while True:
            try:
                plc.write(GROUP, OFF_STREAM, p, kind)
                break
            except pyads.ADSError as e:
                if e.err_code != BUSY:
                    raise
                if t0 is not None:
                    busy += 1
        now = time.perf_counter()
        if t0 is None:
            if now - start >= 0.5:
                t0 = now
            continue
        sent += len(p)
        if now - t0 >= seconds:
            break
    elapsed = time.perf_counter() - t0
    plc.close()
    pyads.close_port()
    rate = sent / elapsed
    print(json.dumps({"client": "pyads " + pyads.__version__, "bytes": sent,
                      "seconds": round(elapsed, 3), "bytes_per_s": round(rate),
                      "percent_of_4094_per_ms": round(100 * rate / NOMINAL, 1),
                      "busy": busy}))


if __name__ == "__main__":
    main()
