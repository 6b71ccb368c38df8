"""A signal that arrives while native code (llvmlite, during a numba compile) has called back into
Python is not raised there -- ctypes would print and drop the exception and the native code would go
on in a state it did not expect -- but delivered again once the callback has returned."""
import os
import signal
import sys
import time

from cnclab.fileio import InterruptReport, in_native_callback

_FAKE = f"{os.sep}site-packages{os.sep}llvmlite{os.sep}binding{os.sep}executionengine.py"


def _in_fake_callback(fn):
    """Run ``fn(frame)`` from a frame whose code claims to be llvmlite's callback module."""
    out = {}
    exec(compile("out['r'] = fn(sys._getframe())", _FAKE, "exec"), {"fn": fn, "sys": sys, "out": out})
    return out["r"]


def test_native_callback_frames_are_recognised():
    assert _in_fake_callback(in_native_callback) is True
    assert in_native_callback(sys._getframe()) is False


def test_signal_in_a_native_callback_is_raised_after_it_returns():
    run = InterruptReport([])
    raised_in_callback = False
    with run:
        try:
            _in_fake_callback(lambda fr: run._handler(signal.SIGINT, fr))   # must not raise here
        except KeyboardInterrupt:
            raised_in_callback = True
        try:
            t0 = time.monotonic()
            while time.monotonic() - t0 < 5.0:      # the redelivered SIGINT arrives after ~0.05 s
                time.sleep(0.01)
            late = False
        except KeyboardInterrupt:
            late = True
    assert not raised_in_callback
    assert late and run.signum == signal.SIGINT
