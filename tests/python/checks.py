"""What the pyads test scripts share: a failed check ends the script with a message, and a
wait polls a condition with a deadline (never a bare sleep)."""

import sys
import time


def check(cond, what):
    if not cond:
        print("FAILED: " + what, file=sys.stderr)
        sys.exit(1)


def wait_for(what, pred, timeout=20.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        v = pred()
        if v:
            return v
        time.sleep(0.01)
    check(False, "timed out waiting for " + what)


def open_connections(netid, addr):
    """pyads' router port with the test client's NetId, and an open connection to each port
    of the server: the system service (10000), the PLC (851) and the CNC (553)."""
    import pyads

    pyads.open_port()
    pyads.set_local_address("10.1.2.3.1.1")
    conns = tuple(pyads.Connection(netid, port, addr) for port in (10000, 851, 553))
    for c in conns:
        c.open()
    return conns


# pyads frees a notification's C callback as soon as it has deleted the notification
# (pyads_ex.adsSyncDelDeviceNotificationReqEx pops it from callback_store), while AdsLib's
# dispatcher thread may still call it: the thread finds the notification under its lock and
# calls it after letting go (Beckhoff/ADS AdsLib/NotificationDispatcher.cpp, Run). A sample
# that arrived then crashed the interpreter with SIGSEGV, seen with 1 ms notifications about
# once in tens of runs. The callbacks are kept for the rest of the process.
_KEPT_CALLBACKS = []


def delete_notification(conn, handles):
    """`conn.del_device_notification(*handles)`, pyads' C callbacks kept alive after it."""
    import pyads

    _KEPT_CALLBACKS.extend(pyads.pyads_ex.callback_store.values())
    conn.del_device_notification(*handles)
