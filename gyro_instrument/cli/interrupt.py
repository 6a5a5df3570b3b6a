"""Ctrl-C in a ``gyro-instrument`` process: always the one line ``gyro-instrument: interrupted``
and exit status 130, wherever the SIGINT lands (used by :func:`gyro_instrument.cli.guarded` and the
two entry points, ``python -m gyro_instrument.cli`` and the ``gyro-instrument`` console script).

Three ways Python alone gets it wrong, each seen in a fuzz of 60 Ctrl-Cs 0.05–0.9 s after start
(``estimate foucault_pantheon``, imports then the run):

* an extension module being imported turns the KeyboardInterrupt into an ImportError (numpy's C
  core interrupted while it imports ``datetime``: "PyCapsule_Import could not import module";
  scipy's pybind11 HiGHS module: "initialization failed"), which printed a traceback, exit 1.
  :class:`SigintWatch` notes every SIGINT, and an exception raised after one is an interrupt;
* a SIGINT landing in a finalizer (``__del__``: llvmlite's) is reported as "Exception ignored"
  with a traceback and then lost: the run went on to the end. The watch's unraisable hook keeps
  that report quiet and sends SIGINT again to the main thread, 10 ms later from a timer thread
  (raised inside the hook it would be swallowed the same way; ``_thread.interrupt_main`` would not
  wake a main thread blocked in a system call);
* an interrupt that landed inside an extension's own Python run (CPython's ``run_eval_code_obj``)
  leaves the interpreter's "unhandled KeyboardInterrupt" flag set, and Python then ends by killing
  itself with SIGINT: status −2, not 130, in 6 of 60 runs. :func:`exit_interrupted` clears that
  flag (CPython 3.11's exported ``_Py_UnhandledKeyboardInterrupt``) so that the process ends
  normally with 130; where the flag cannot be reached it ends the process itself
  (:func:`exit_now`), which skips the finalizers (a process pool's semaphores are then reported
  leaked by multiprocessing's resource tracker).
"""

import atexit
import os
import signal
import sys
import threading

#: The exit status of an interrupted command (128 + SIGINT).
EXIT_INTERRUPTED = 130
LINE = "gyro-instrument: interrupted"


class SigintWatch:
    """While active (``with``): SIGINT raises KeyboardInterrupt as Python's default handler does and
    is noted (``hit``); a KeyboardInterrupt a finalizer swallowed is raised again in the main thread.
    Main thread only; elsewhere it does nothing."""

    def __init__(self):
        self.hit = 0
        self._previous = self._hook = None
        self._active = threading.current_thread() is threading.main_thread()

    def _on_sigint(self, signum, frame):
        self.hit += 1
        raise KeyboardInterrupt

    def _unraisable(self, unraisable):
        if isinstance(unraisable.exc_value, KeyboardInterrupt):
            # raised again in the main thread once this hook has returned (raised here, inside the
            # hook, it would be swallowed and reported like the first)
            main = threading.main_thread().ident
            threading.Timer(0.01, signal.pthread_kill, (main, signal.SIGINT)).start()
            return
        self._hook(unraisable)

    def __enter__(self):
        if self._active:
            self._previous = signal.signal(signal.SIGINT, self._on_sigint)
            self._hook, sys.unraisablehook = sys.unraisablehook, self._unraisable
        return self

    def __exit__(self, *exc):
        if self._active:
            sys.unraisablehook = self._hook
            signal.signal(signal.SIGINT, self._previous)
        return False


def guarded_import(load) -> object:
    """``load()`` (the CLI's heavy imports) under a :class:`SigintWatch`: a Ctrl-C during it raises
    KeyboardInterrupt even when the extension being imported turned it into another error. Returns
    what ``load`` returns; SIGINT's previous handler is restored after."""
    with SigintWatch() as watch:
        try:
            return load()
        except BaseException as exc:
            if watch.hit and not isinstance(exc, KeyboardInterrupt):
                raise KeyboardInterrupt from exc
            raise


def _clear_unhandled_interrupt() -> bool:
    """Clear CPython's "unhandled KeyboardInterrupt" flag; False where it is not reachable."""
    import ctypes
    try:
        ctypes.c_int.in_dll(ctypes.pythonapi, "_Py_UnhandledKeyboardInterrupt").value = 0
    except (ValueError, AttributeError, OSError):
        return False
    return True


def exit_interrupted(status) -> int:
    """Make ``status`` the process's exit status: the interpreter's "unhandled KeyboardInterrupt"
    flag cleared and ``status`` returned for ``sys.exit`` (a normal shutdown, finalizers run), or,
    where the flag is out of reach, :func:`exit_now`."""
    if not _clear_unhandled_interrupt():
        exit_now(status)
    return status


def exit_now(status) -> None:
    """End the process with ``status`` at once, SIGINT ignored: stdout and stderr flushed and the
    ``atexit`` functions run (multiprocessing's clean-up of its children among them), then
    ``os._exit`` — so an interpreter flag left by an interrupt cannot turn 130 into death by SIGINT."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        atexit._run_exitfuncs()
    finally:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        os._exit(status)


def interrupted_while_importing() -> None:
    """The one line, then exit 130 (:func:`exit_interrupted`): a Ctrl-C before the CLI's modules are
    imported."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    print(LINE, file=sys.stderr)
    sys.exit(exit_interrupted(EXIT_INTERRUPTED))
