"""ncchannel's ADS server seen by unmodified pyads (Beckhoff's adslib underneath).

Run against a running server:

    NCCHANNEL_ADS_ADDR=127.0.0.1:48898 python tests/python/test_pyads.py

NCCHANNEL_ADS_ADDR (required) is the server's TCP address; NCCHANNEL_ADS_NETID (default
127.0.0.1.1.1) the target NetId. The channel must be channel 1 and must not be streaming when
the test starts (e.g. `ncchannel serve` without --start, or the real channels that
`cargo test --test ads_clients -- --ignored ads_pyads` starts).
"""

import ctypes
import os
import struct
import threading
import time
import unittest

import pyads

from checks import delete_notification

ADDR = os.environ.get("NCCHANNEL_ADS_ADDR")
NETID = os.environ.get("NCCHANNEL_ADS_NETID", "127.0.0.1.1.1")
PORT_CNC = 553
GROUP = 0x20101  # channel 1
OFF_STREAM = 0x90
OFF_MODE_STATE = 0x103
OFF_COMMAND_MODE = 0x104
OFF_RESET = 0x13C
OFF_ERROR_MESSAGE = 0x26
OFF_STREAM_FILL = 0x8001
PORT_SDA = 552
GROUP_SDA = 0x122301  # decoder class of channel 1
OFF_SDA_WRITE_BY_NAME = 0x4A
OFF_SDA_READ_BY_NAME = 0x48
DINT2 = ctypes.c_int32 * 2
UDINT2 = ctypes.c_uint32 * 2


def packet(n_bytes):
    """One stream packet of whole CR LF lines, exactly n_bytes long."""
    line = b"N10 G01 X1 Y2 F1000 (" + b"p" * (n_bytes - 24) + b")\r\n"
    assert len(line) == n_bytes, len(line)
    return line


def write_bytes(plc, group, offset, data):
    plc.write(group, offset, list(data), ctypes.c_uint8 * len(data))


class PyadsAgainstNcchannel(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        if not ADDR:
            raise unittest.SkipTest("NCCHANNEL_ADS_ADDR not set")
        pyads.open_port()
        pyads.set_local_address("10.1.2.3.1.1")
        cls.plc = pyads.Connection(NETID, PORT_CNC, ADDR)
        cls.plc.open()

    @classmethod
    def tearDownClass(cls):
        cls.plc.close()
        pyads.close_port()

    def setUp(self):
        self.plc.write(GROUP, OFF_RESET, 1, pyads.PLCTYPE_UDINT)

    def test_device_info_and_state(self):
        name, version = self.plc.read_device_info()
        self.assertTrue(name.startswith("ncchannel"), name)
        ads_state, _device_state = self.plc.read_state()
        self.assertEqual(ads_state, pyads.ADSSTATE_RUN)

    def test_mode_state_is_two_dints(self):
        mode, state = self.plc.read(GROUP, OFF_MODE_STATE, DINT2)
        self.assertIn(mode, range(1, 6))
        self.assertEqual(state, 3)  # READY after reset

    def test_stream_write_then_busy_0x708(self):
        write_bytes(self.plc, GROUP, OFF_STREAM, packet(100))
        busy = None
        for _ in range(50):
            try:
                write_bytes(self.plc, GROUP, OFF_STREAM, packet(992))
            except pyads.ADSError as e:
                busy = e.err_code
                break
        self.assertEqual(busy, 0x708)
        used, free = self.plc.read(GROUP, OFF_STREAM_FILL, UDINT2)
        self.assertGreater(used, 3000)
        self.assertEqual(used + free, 4094)

    def test_missing_crlf_is_0x706_with_error_21476(self):
        with self.assertRaises(pyads.ADSError) as ctx:
            write_bytes(self.plc, GROUP, OFF_STREAM, b"N10 X1\n")
        self.assertEqual(ctx.exception.err_code, 0x706)
        text = self.plc.read(GROUP, OFF_ERROR_MESSAGE, pyads.PLCTYPE_STRING, check_length=False)
        self.assertIn("21476", text)

    def test_unknown_offset_and_group(self):
        with self.assertRaises(pyads.ADSError) as ctx:
            self.plc.read(GROUP, 0x7777, pyads.PLCTYPE_UDINT)
        self.assertEqual(ctx.exception.err_code, 0x703)
        with self.assertRaises(pyads.ADSError) as ctx:
            self.plc.read(0x4020, 0, pyads.PLCTYPE_UDINT)
        self.assertEqual(ctx.exception.err_code, 0x702)

    def test_ve_variable_write_then_read_write(self):
        """V.E. variables in the SDA task: write by name (name, NUL, LREAL), read by name."""
        sda = pyads.Connection(NETID, PORT_SDA, ADDR)
        sda.open()
        try:
            data = b"V.E.pyads_test\0" + struct.pack("<d", 4.75)
            write_bytes(sda, GROUP_SDA, OFF_SDA_WRITE_BY_NAME, data)
            value = sda.read_write(
                GROUP_SDA, OFF_SDA_READ_BY_NAME, pyads.PLCTYPE_LREAL, "V.E.pyads_test",
                pyads.PLCTYPE_STRING
            )
            self.assertEqual(value, 4.75)
        finally:
            sda.close()

    def test_notification_on_mode_change(self):
        seen = []
        got = threading.Event()

        def callback(notification, _data):
            _handle, _timestamp, value = self.plc.parse_notification(notification, DINT2)
            seen.append(tuple(value))
            got.set()

        attr = pyads.NotificationAttrib(8, trans_mode=pyads.ADSTRANS_SERVERONCHA,
                                        max_delay=1, cycle_time=1)
        handles = self.plc.add_device_notification((GROUP, OFF_MODE_STATE), attr, callback)
        try:
            self.assertTrue(got.wait(5), "no initial notification")
            first_mode = seen[-1][0]
            new_mode = 3 if first_mode != 3 else 2
            got.clear()
            self.plc.write(GROUP, OFF_COMMAND_MODE, new_mode, pyads.PLCTYPE_DINT)
            deadline = time.time() + 5
            while time.time() < deadline and seen[-1][0] != new_mode:
                got.wait(0.1)
            self.assertEqual(seen[-1][0], new_mode)
        finally:
            delete_notification(self.plc, handles)


if __name__ == "__main__":
    unittest.main(verbosity=2)
