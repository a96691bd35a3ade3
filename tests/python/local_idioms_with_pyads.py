"""ncchannel serve on its default addresses seen by unmodified pyads with its documented calls:
the Linux quick start's `add_route_to_plc` (UDP 48899), `adsGetNetIdForPLC`, and
`pyads.Connection('127.0.0.1.1.1', 851)` without an IP address (pyads takes it from the
NetId) and without `set_local_address`. Run by tests/ads_clients/ads_local_idioms.rs against
a server on 127.0.0.1:48898 (TCP) and 127.0.0.1:48899 (UDP). Prints one JSON line.
"""

import json

import pyads

seen = {}
seen["route_added"] = pyads.add_route_to_plc(
    "10.1.2.3.1.1", "127.0.0.1", "127.0.0.1", "Administrator", "1", route_name="ncchannel"
)
seen["net_id"] = pyads.pyads_ex.adsGetNetIdForPLC("127.0.0.1")
plc = pyads.Connection("127.0.0.1.1.1", pyads.PORT_TC3PLC1)
plc.open()
seen["device"] = plc.read_device_info()[0]
seen["state"] = list(plc.read_state())
plc.close()
own = pyads.Connection(seen["net_id"], pyads.PORT_TC3PLC1, "127.0.0.1")
own.open()
seen["device_by_own_net_id"] = own.read_device_info()[0]
own.close()
print(json.dumps(seen))
