"""A signal that arrives while native code (llvmlite, during a numba compile) has called back into
Python is not raised there -- ctypes would print and drop the exception and the native code would go
on in a state it did not expect -- but delivered again once the callback has returned."""
import os
import signal
import sys
import time

from cnclab.fileio import InterruptReport, in_native_callback

_SITE = f"{os.sep}site-packages{os.sep}"
_FAKE = f"{_SITE}llvmlite{os.sep}binding{os.sep}executionengine.py"


def _in_fake(fn, filename=_FAKE, name="_raw_object_cache_notify"):
    """Run ``fn(frame)`` from a function named ``name`` whose code claims to be in ``filename`` (the
    frame passed is a callee's: the check walks up to the callers)."""
    src = f"def {name}(fn, sys):\n    return (lambda: fn(sys._getframe()))()\n"
    ns = {}
    exec(compile(src, filename, "exec"), ns)
    return ns[name](fn, sys)


def _in_fake_callback(fn):
    return _in_fake(fn)


def test_native_callback_frames_are_recognised():
    assert _in_fake_callback(in_native_callback) is True
    assert _in_fake(in_native_callback, name="_raw_object_cache_getbuffer") is True
    assert in_native_callback(sys._getframe()) is False


def test_ordinary_ctypes_and_llvmlite_frames_are_not_callbacks():
    """stdlib ctypes (loading a library, find_library) and llvmlite's other Python code (its ffi call
    wrappers, object finalizers) are called from Python, not from native code: an interrupt there is
    raised at once (the former rule matched every path with a ``ctypes`` or ``llvmlite`` folder)."""
    import ctypes

    stdlib_ctypes = os.path.join(os.path.dirname(ctypes.__file__), "__init__.py")
    assert _in_fake(in_native_callback, stdlib_ctypes, "__init__") is False
    assert _in_fake(in_native_callback, stdlib_ctypes, "_raw_object_cache_notify") is False   # same name, other file
    assert _in_fake(in_native_callback, f"{_SITE}llvmlite{os.sep}binding{os.sep}ffi.py", "__call__") is False
    assert _in_fake(in_native_callback, _FAKE, "close") is False
    # the real hooks are where the rule says (a new llvmlite that moves them fails here)
    from llvmlite.binding import executionengine as ee

    for name in ("_raw_object_cache_notify", "_raw_object_cache_getbuffer"):
        code = getattr(ee.ExecutionEngine, name).__code__
        assert code.co_name == name and code.co_filename.endswith(os.path.join("llvmlite", "binding", "executionengine.py"))


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
