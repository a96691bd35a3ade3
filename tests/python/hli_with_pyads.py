"""The PLC's HLI (port 851), the COM task (553) and the GEO task (551) seen by unmodified pyads
against the real channels (`ncchannel serve`-like, 1 ms ticks).

    NCCHANNEL_ADS_ADDR=127.0.0.1:48898 python tests/python/hli_with_pyads.py

Channel 1 must be READY with streaming program `streaming.nc` configured and no program
`missing.nc`. Prints one JSON line with what it saw; exits non-zero on a failed check.

Symbols and layouts as TwinSharp uses them (kimblad/TwinSharp TwinSharp/CNC/
OperationModeManager.cs, ErrorManagement.cs, Structs.cs); control-unit protocol as Beckhoff
infosys tf5200_hli_interface/174725259.html.
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
MS = "HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state"
ERR = "HLI_Global_Variables.gpCh[0]^.mc_error"
CH = 0x120101
TRANSITION = ctypes.c_uint8 * 327
ERROR_SATZ = ctypes.c_uint8 * 942
ADSERR_BUSY = 0x708


def transition(to_mode, to_state, parameter=b""):
    """HLI_PROC_TRANS_TO_MODE_STATE: 5 x UDINT, DINT fill, char[299], DINT fill."""
    b = bytearray(327)
    struct.pack_into("<5I", b, 0, 0, 0, to_mode, to_state, 0)
    b[24:24 + len(parameter)] = parameter
    return list(b)


def command(plc, to_mode, to_state, parameter=b""):
    """The command unit as TwinSharp drives it: command_w, then command_semaphor_rw TRUE."""
    plc.write_by_name(MS + ".command_w", transition(to_mode, to_state, parameter), TRANSITION)
    plc.write_by_name(MS + ".command_semaphor_rw", True, pyads.PLCTYPE_BOOL)


def watch(plc, lock, name, plc_type, cycle_ms):
    """An on-change notification by symbol name (as TwinSharp's AddDeviceNotificationEx):
    the list its values arrive in, and the handles to delete it with."""
    values = []

    def on_change(notification, _name):
        _h, _ts, value = plc.parse_notification(notification, plc_type)
        with lock:
            values.append(value)

    size = ctypes.sizeof(plc_type)
    attr = pyads.NotificationAttrib(size, trans_mode=pyads.ADSTRANS_SERVERONCHA, cycle_time=cycle_ms)
    return values, plc.add_device_notification(name, attr, on_change)


def main():
    pyads.open_port()
    pyads.set_local_address("10.1.2.3.1.1")
    plc = pyads.Connection(NETID, 851, ADDR)
    com = pyads.Connection(NETID, 553, ADDR)
    geo = pyads.Connection(NETID, 551, ADDR)
    for c in (plc, com, geo):
        c.open()
    seen = {}

    # TwinSharp's constructor: enable_w := TRUE; a PLC is there.
    plc.write_by_name(MS + ".enable_w", True, pyads.PLCTYPE_BOOL)
    plc.write_by_name("HLI_Global_Variables.gpCh[0]^.head.plc_present_w", True, pyads.PLCTYPE_BOOL)
    check(geo.read(0x123301, 0x0E, pyads.PLCTYPE_BOOL) is True, "GEO mirrors plc_present_w")
    # Without a type pyads asks for the symbol info (0xF009) first.
    check(plc.read_by_name(MS + ".state_r.state") == 3, "READY before the start")

    lock = threading.Lock()
    states, state_handles = watch(plc, lock, MS + ".state_r.state", pyads.PLCTYPE_UDINT, 1)
    wait_for("the first state sample", lambda: len(states) > 0)

    # The command unit: command_w, then command_semaphor_rw TRUE; the CNC takes it.
    command(plc, 2, 4, b"streaming.nc")
    check(plc.read_by_name(MS + ".command_semaphor_rw", pyads.PLCTYPE_BOOL) is False,
          "the CNC cleared command_semaphor_rw")
    state_r = plc.read_by_name(MS + ".state_r", pyads.PLCTYPE_UDINT * 2)
    check(list(state_r) == [2, 4], "state_r = AUTOMATIC/ACTIVE, got %r" % (list(state_r),))
    check(geo.read(0x123301, 0x1F, pyads.PLCTYPE_UDINT) == 4, "GEO HLD state")
    check(geo.read(0x123301, 0x20, pyads.PLCTYPE_UDINT) == 2, "GEO HLD mode")
    check(geo.read(0x123301, 0x2C, pyads.PLCTYPE_UDINT) == 2, "GEO mirrors command_w.to_mode")
    check(com.read(CH, 0x12, pyads.PLCTYPE_STRING) == "streaming.nc", "mc_active_program_name_r")

    # A stream runs: whole CR LF lines, 0x708 retried.
    lines = ["N1 G01 F6000"] + ["N%d P%d=%d" % (i, 1 + i % 20, i) for i in range(2, 400)]
    lines += ["N400 X150", "N410 X0", "N420 M30"]
    busy = 0
    packet = []
    size = 0
    packets = []
    for line in lines:
        raw = (line + "\r\n").encode()
        if size + len(raw) > 900:
            packets.append(b"".join(packet))
            packet, size = [], 0
        packet.append(raw)
        size += len(raw)
    packets.append(b"".join(packet))
    for p in packets:
        while True:
            try:
                com.write(CH, 0x90, list(p), ctypes.c_uint8 * len(p))
                break
            except pyads.ADSError as e:
                check(e.err_code == ADSERR_BUSY, "stream write error %r" % e)
                busy += 1
                time.sleep(0.001)
    seen["busy"] = busy

    # Override at 0x09 (0.1 %) changes the path velocity the interpolator reports.
    group, offset = geo.read_write(0x121900, 0, pyads.PLCTYPE_UDINT * 2, [1, 0], pyads.PLCTYPE_DINT * 2)
    check((group, offset) == (0x121301, 0), "interpolator address (%x, %x)" % (group, offset))
    check(geo.read(group, 0, pyads.PLCTYPE_UDINT) > 0, "interpolator element count")

    def velocity():
        return geo.read(group, 0x15, pyads.PLCTYPE_LREAL)

    wait_for("full speed 100 mm/s", lambda: abs(velocity() - 100000.0) < 1.0)
    check(abs(com.read(CH, 0x13, pyads.PLCTYPE_LREAL) - 100000.0) < 1e-6, "mc_command_feedrate_r µm/s")
    com.write(CH, 0x09, 500, pyads.PLCTYPE_UINT)
    check(com.read(CH, 0x0C, pyads.PLCTYPE_UINT) == 500, "mc_active_feedrate_override_r")
    wait_for("half speed at 50 %", lambda: abs(velocity() - 50000.0) < 1.0)
    check(abs(com.read(CH, 0x14, pyads.PLCTYPE_LREAL) - 50000.0) < 1e-6, "mc_active_feedrate_r")
    seen["velocity_at_50"] = velocity()
    com.write(CH, 0x09, 1000, pyads.PLCTYPE_UINT)

    wait_for("program end", lambda: plc.read_by_name(MS + ".state_r.state", pyads.PLCTYPE_UDINT) == 3)
    check(com.read(CH, 0x0D, pyads.PLCTYPE_UDINT) == len(lines), "mc_block_count_r counts every line")
    time.sleep(0.1)
    delete_notification(plc, state_handles)
    with lock:
        seen["states"] = list(states)
    check(seen["states"][:2] == [3, 4] and seen["states"][-1] == 3,
          "state_r followed READY → ACTIVE → READY: %r" % seen["states"])

    # While enable_w is TRUE the PLC operates the unit: an HMI's start over COM is not executed
    # but handed to the PLC in request_r with request_semaphor_rw TRUE.
    com.write(CH, 0x108, list(b"other.nc\0"), ctypes.c_uint8 * 9)
    com.write(CH, 0x105, 4, pyads.PLCTYPE_DINT)
    check(plc.read_by_name(MS + ".request_semaphor_rw", pyads.PLCTYPE_BOOL) is True, "request posted")
    req = bytes(plc.read_by_name(MS + ".request_r", TRANSITION))
    check(struct.unpack_from("<5I", req, 0) == (2, 3, 2, 4, 1), "request_r %r" % (struct.unpack_from("<5I", req, 0),))
    check(req[24:33] == b"other.nc\0", "request_r.parameter")
    check(geo.read(0x123301, 0x27, pyads.PLCTYPE_UDINT) == 4, "GEO mirrors request_r.to_state")
    check(plc.read_by_name(MS + ".state_r.state", pyads.PLCTYPE_UDINT) == 3, "not executed")
    try:
        com.write(CH, 0x105, 4, pyads.PLCTYPE_DINT)
        check(False, "a second request before the PLC took the first")
    except pyads.ADSError as e:
        check(e.err_code == ADSERR_BUSY, "0x708 until the PLC takes the request")
    plc.write_by_name(MS + ".request_semaphor_rw", False, pyads.PLCTYPE_BOOL)
    # The PLC hands the unit back to the CNC.
    plc.write_by_name(MS + ".enable_w", False, pyads.PLCTYPE_BOOL)

    # Errors: one record posted with the semaphore TRUE, the next only after it is cleared.
    sem_values, sem_handles = watch(plc, lock, ERR + ".semaphor_rw", pyads.PLCTYPE_BOOL, 50)
    try:
        com.write(CH, 0x90, list(b"N10 X1\n"), ctypes.c_uint8 * 7)
        check(False, "a line without CR LF is refused")
    except pyads.ADSError as e:
        check(e.err_code == 0x706, "no CR LF: 0x706")
    check(list(plc.read_by_name(MS + ".state_r", pyads.PLCTYPE_UDINT * 2))[1] == 6, "ERROR state")
    wait_for("semaphore notification", lambda: True in sem_values)
    rec = bytes(plc.read_by_name(ERR + ".satz_r", ERROR_SATZ))
    check(struct.unpack_from("<I", rec, 0)[0] == 21476, "error_id 21476")
    check(plc.read_by_name(ERR + ".satz_r.kopf.error_id", pyads.PLCTYPE_UDINT) == 21476, "kopf.error_id")
    check(struct.unpack_from("<H", rec, 56)[0] == 1, "cnc_channel 1")
    # A second error while the first is not acknowledged: the record stays.
    com.write(CH, 0x13C, [], ctypes.c_uint8 * 0)
    com.write(CH, 0x108, list(b"missing.nc\0"), ctypes.c_uint8 * 11)
    try:
        com.write(CH, 0x105, 4, pyads.PLCTYPE_DINT)
    except pyads.ADSError:
        pass
    check(com.read(CH, 0x109, pyads.PLCTYPE_DINT) == 6, "start of a missing program: ERROR")
    second = com.read(CH, 0x26, pyads.PLCTYPE_STRING)
    check(not second.startswith("21476"), "mc_error_message_r shows the second error: %r" % second)
    check(plc.read_by_name(ERR + ".satz_r.kopf.error_id", pyads.PLCTYPE_UDINT) == 21476,
          "record unchanged until acknowledged")
    plc.write_by_name(ERR + ".semaphor_rw", False, pyads.PLCTYPE_BOOL)
    check(plc.read_by_name(ERR + ".semaphor_rw", pyads.PLCTYPE_BOOL) is True, "next record posted")
    second_id = plc.read_by_name(ERR + ".satz_r.kopf.error_id", pyads.PLCTYPE_UDINT)
    check(second_id == int(second.split()[0]), "second error_id %d = %r" % (second_id, second))
    plc.write_by_name(ERR + ".semaphor_rw", False, pyads.PLCTYPE_BOOL)
    check(plc.read_by_name(ERR + ".semaphor_rw", pyads.PLCTYPE_BOOL) is False, "no third error")
    delete_notification(plc, sem_handles)
    seen["errors"] = [21476, second_id]

    # Reset through the HLI: to_state 15 ("Resetting").
    command(plc, 0, 15)
    check(list(plc.read_by_name(MS + ".state_r", pyads.PLCTYPE_UDINT * 2))[1] == 3, "reset → READY")

    for c in (plc, com, geo):
        c.close()
    pyads.close_port()
    print(json.dumps(seen))


if __name__ == "__main__":
    main()
