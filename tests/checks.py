"""What the Python tests share (as tests/testing.h for the C ones): one line per check, and the failures kept."""

failures = []


def check(ok, what):
    """Print one line for a check (ok or FAIL) and remember a failure; returns ok."""
    print(("ok   " if ok else "FAIL ") + what, flush=True)
    if not ok:
        failures.append(what)
    return ok
