"""The ``rigsim`` command line.

Exit codes: 0 success; 2 bad input or a run that cannot go on (one sentence on stderr,
nothing written); 1 a recording process that failed for another reason (``rigsim run --rrd``,
one sentence, nothing written); 130 interrupted, 143 terminated (nothing written: every command that writes a
folder builds it beside the target and renames it at the end, :mod:`rigsim.scenarios.core.outputs`).
"""

from __future__ import annotations

import os
import sys

from rigsim.scenarios.cli.parser import EXAMPLES, build_parser

__all__ = ["main", "exit_main", "build_parser", "EXAMPLES", "INTERRUPTED"]


class _SigtermAsInterrupt:
    """While installed, SIGTERM raises KeyboardInterrupt in the main thread, so a terminated run
    stops as after Ctrl-C (pool workers terminated, a sweep's finished cases kept); ``received``
    tells the two apart. Outside the main thread nothing is installed.

    A handler's exception can be lost: Python runs signal handlers between bytecodes, also inside
    a ctypes callback, which hands the exception to ``sys.unraisablehook`` ("Exception ignored")
    and goes on (numba loading its cached callbacks through llvmlite's object-cache callback: a
    command terminated then runs its whole 600 s run and exits 0, measured without the re-send 2
    times in 30 with SIGTERM 0.05-1.5 s after the start). While installed, this also takes that hook: a lost
    interrupt of its own is sent again, as SIGTERM after :data:`RESEND_S`, until one arrives in
    code that lets it through (:meth:`acknowledge` or :meth:`restore` stop it; late copies are
    ignored). An interrupt that was not lost is never repeated, so cleanup runs undisturbed."""

    #: s before a lost interrupt's SIGTERM is sent again.
    RESEND_S = 0.05
    #: The KeyboardInterrupt's message: how the unraisable hook knows its own interrupt.
    MESSAGE = "terminated (SIGTERM)"

    def __init__(self) -> None:
        import signal
        import threading

        self.received, self._signal, self._previous = False, signal, None
        self._caught, self._hook = threading.Event(), None
        try:
            self._previous = (signal.signal(signal.SIGTERM, self._handle),)
        except ValueError:  # not the main thread
            return
        self._hook = sys.unraisablehook
        sys.unraisablehook = self._unraisable

    def _handle(self, signum, frame) -> None:
        if self._caught.is_set():  # a late copy: the interrupt is being handled already
            return
        self.received = True
        raise KeyboardInterrupt(self.MESSAGE)

    def _unraisable(self, unraisable) -> None:
        """``sys.unraisablehook``: our interrupt, lost where exceptions cannot propagate: send it again."""
        exc = unraisable.exc_value
        if not (self.received and isinstance(exc, KeyboardInterrupt) and exc.args == (self.MESSAGE,)):
            (self._hook or sys.__unraisablehook__)(unraisable)
            return
        import os
        import threading

        def resend() -> None:
            if not self._caught.wait(self.RESEND_S):
                os.kill(os.getpid(), self._signal.SIGTERM)

        threading.Thread(target=resend, name="rigsim-sigterm-resend", daemon=True).start()

    def acknowledge(self) -> None:
        """The interrupt was caught: late copies are ignored and none is sent again."""
        self._caught.set()

    def restore(self) -> None:
        self.acknowledge()
        if self._previous is not None:
            self._signal.signal(self._signal.SIGTERM, self._previous[0] or self._signal.SIG_DFL)
            self._previous = None
        if self._hook is not None:
            sys.unraisablehook, self._hook = self._hook, None


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``rigsim`` console command; returns the exit code (SIGTERM: the run
    stops as for Ctrl-C, "rigsim: terminated" on stderr, 143)."""
    args = build_parser().parse_args(argv)  # --help and bad options end here, before the imports below
    # The commands draw nothing with MuJoCo (recordings are rerun's): its import then skips loading
    # OpenGL (glfw), ~0.06 s of every process's start (benchmarks/startup.py); a value set is kept.
    os.environ.setdefault("MUJOCO_GL", "disable")
    from rigsim.errors import RigsimError

    sigterm = _SigtermAsInterrupt()
    try:
        return args.func(args)
    except RigsimError as exc:  # every one-sentence refusal, and MuJoCo's warnings as errors
        print(f"rigsim: error: {exc}", file=sys.stderr)
        return 2
    except ValueError as exc:  # parameter validation of the model layers
        print(f"rigsim: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"rigsim: error: cannot write output: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        sigterm.acknowledge()
        if sigterm.received:
            print("rigsim: terminated", file=sys.stderr)
            return 143
        print("rigsim: interrupted", file=sys.stderr)
        return 130
    finally:
        sigterm.restore()


#: Exit codes of an interrupted command (Ctrl-C, SIGTERM), whose cleanup :func:`main` has done.
INTERRUPTED = (130, 143)


def exit_main(code: int) -> None:
    """End ``python -m rigsim.scenarios.cli.main`` with ``code``. After an interrupt (:data:`INTERRUPTED`)
    the process ends at once (its outputs are removed and its workers stopped; the standard
    streams are flushed): CPython ends a ``-m`` run by SIGINT, whatever the code, once a
    KeyboardInterrupt has passed through a nested ``PyRun_String`` (MuJoCo's callback module runs
    one while the hydraulics are installed), so without ``os._exit`` SIGTERM can end the command as
    killed by SIGINT after it has printed "rigsim: terminated" (measured: 3 times in 30 with SIGTERM
    0.05-1.5 s after the start). The ``rigsim`` script exits by the code as it is."""
    if code in INTERRUPTED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    exit_main(main())
