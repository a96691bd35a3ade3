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
