"""1 ms notifications counted against the tick counter with unmodified pyads: an on-change
handle on the COM task's `cnc_tick_counter_r` (port 553) and a cyclic one on the GEO task's
tick counter (port 551), both with a 1 ms cycle while the channels tick every 1 ms. Each must
see every tick: consecutive samples one apart, none missing, over 500 samples each.

    NCCHANNEL_ADS_ADDR=127.0.0.1:48898 python tests/python/tick_notifications_with_pyads.py

Objects as docs/ads.md lists them. Prints one JSON line with what it saw; exits non-zero on
a failed check.
"""

import json
import os
import threading

import pyads

from checks import check, delete_notification, wait_for

ADDR = os.environ["NCCHANNEL_ADS_ADDR"]
NETID = os.environ.get("NCCHANNEL_ADS_NETID", "127.0.0.1.1.1")
COM_TICK_COUNTER = (0x120101, 0x251)
GEO_TICK_COUNTER = (0x120300, 0x07)
SAMPLES = 500


def subscribe(conn, lock, address, trans_mode):
    """A 1 ms notification of a UDINT at `address`: the list its values arrive in, and the
    handles to delete it with."""
    values = []

    def on_sample(notification, _name):
        _h, _ts, value = conn.parse_notification(notification, pyads.PLCTYPE_UDINT)
        with lock:
            values.append(value)

    attr = pyads.NotificationAttrib(4, trans_mode=trans_mode, cycle_time=1)
    return values, conn.add_device_notification(address, attr, on_sample)


def gaps(values):
    """Steps between consecutive samples that are not +1."""
    return [(a, b) for a, b in zip(values, values[1:]) if b != a + 1]


def main():
    pyads.open_port()
    pyads.set_local_address("10.1.2.3.1.1")
    com = pyads.Connection(NETID, 553, ADDR)
    geo = pyads.Connection(NETID, 551, ADDR)
    com.open()
    geo.open()
    lock = threading.Lock()
    on_change, on_change_handles = subscribe(
        com, lock, COM_TICK_COUNTER, pyads.ADSTRANS_SERVERONCHA)
    cyclic, cyclic_handles = subscribe(
        geo, lock, GEO_TICK_COUNTER, pyads.ADSTRANS_SERVERCYCLE)

    def enough():
        with lock:
            return len(on_change) >= SAMPLES and len(cyclic) >= SAMPLES

    wait_for("500 samples of each handle", enough)
    delete_notification(com, on_change_handles)
    delete_notification(geo, cyclic_handles)
    with lock:
        seen_change, seen_cyclic = on_change[:SAMPLES], cyclic[:SAMPLES]
    check(not gaps(seen_change),
          "the 1 ms on-change handle saw every tick: %s" % gaps(seen_change)[:10])
    check(not gaps(seen_cyclic),
          "the 1 ms cyclic handle sampled every cycle: %s" % gaps(seen_cyclic)[:10])
    com.close()
    geo.close()
    pyads.close_port()
    print(json.dumps({
        "on_change": [len(seen_change), seen_change[-1] - seen_change[0]],
        "cyclic": [len(seen_cyclic), seen_cyclic[-1] - seen_cyclic[0]],
    }))


if __name__ == "__main__":
    main()
