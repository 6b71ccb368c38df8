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


def test_ordinary_ctypes_frames_are_not_callbacks():
    """stdlib ctypes (loading a library, find_library) is called from Python, not from native code: an
    interrupt there is raised at once; a folder merely named like numba/llvmlite is not theirs."""
    import ctypes

    stdlib_ctypes = os.path.join(os.path.dirname(ctypes.__file__), "__init__.py")
    assert _in_fake(in_native_callback, stdlib_ctypes, "__init__") is False
    assert _in_fake(in_native_callback, stdlib_ctypes, "_raw_object_cache_notify") is False   # same name, other file
    assert _in_fake(in_native_callback, f"{_SITE}llvmlite_not{os.sep}binding{os.sep}ffi.py", "__call__") is False
    assert _in_fake(in_native_callback, f"{_SITE}numbafied{os.sep}core{os.sep}dispatcher.py", "typeof_pyval") is False
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


def test_numba_and_llvmlite_code_defers_the_signal():
    """numba's dispatcher (C) calls numba's Python code to type arguments and load or compile a kernel:
    a signal there is delivered later (a KeyboardInterrupt raised inside it surfaced as "SystemError:
    CPUDispatcher(...) returned a result with an exception set"). The real package folders count,
    wherever they are installed; callers of such a frame do not."""
    import llvmlite.binding.ffi as ffi
    import numba.core.dispatcher as disp

    assert _in_fake(in_native_callback, disp.__file__, "typeof_pyval") is True
    assert _in_fake(in_native_callback, ffi.__file__, "__call__") is True
    assert in_native_callback(sys._getframe()) is False      # this test's frame: not numba's


def test_signal_in_numba_code_is_raised_after_it_returns():
    import numba.core.dispatcher as disp

    run = InterruptReport([])
    raised_inside, late = _inside_then_late(
        run, lambda: _in_fake(lambda fr: run._handler(signal.SIGINT, fr), disp.__file__, "_compile_for_args"),
        KeyboardInterrupt)
    assert not raised_inside and late


def _inside_then_late(run, trigger, exc_type):
    """Under ``run`` (an InterruptReport): whether ``trigger()`` raised ``exc_type`` at once, and whether
    it was raised within the next 5 s (the signal delivered again)."""
    with run:
        try:
            trigger()
            raised_inside = False
        except exc_type:
            raised_inside = True
        try:
            t0 = time.monotonic()
            while time.monotonic() - t0 < 5.0:
                time.sleep(0.01)
            late = False
        except exc_type:
            late = True
    return raised_inside, late


def test_signal_in_a_finalizer_is_raised_after_it_returns():
    # a SIGTERM arriving in a __del__ (tqdm's, at exit, after the outputs were written: a CI fuzz run)
    # was printed as "Exception ignored in ... __del__" and dropped; deferred, it is raised after the
    # finalizer has returned
    class Finalized:
        def __del__(self):
            seen.append(in_native_callback(sys._getframe()))
            run._handler(signal.SIGTERM, sys._getframe())

    seen = []
    run = InterruptReport([])
    # the object made by the trigger is dropped as the trigger returns: its finalizer runs inside it
    raised_inside, late = _inside_then_late(run, lambda: Finalized() and None, SystemExit)
    assert seen == [True] and not raised_inside and late
