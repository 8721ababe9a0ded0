"""The boundary around the third-party readers of measured data (asammdf, nptdms): nothing of
theirs reaches the console, and whatever goes wrong is one sentence naming the file.

:func:`library_call` is a context manager around every call into such a library reading one
file. During it the library's warnings are ignored, what it prints (``sys.stdout``,
``sys.stderr``) is dropped and its log records (its logger and the children) are kept from the
console; a record saying the file ends before the data its blocks announce (a recording cut
off) refuses the file, even when the library went on reading, since what it read is a part of
the record. Any exception of the library (the types vary by version and by what is wrong with
the file) becomes one :class:`MeasuredDataError`; an asammdf object whose construction failed
is closed at once (:func:`close_half_made`), so that nothing is printed when it is collected
and nothing it made is left behind.
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import warnings

from rigsim.correction.io.measured_core import MeasuredDataError

__all__ = ["library_call", "said", "close_half_made"]

#: What asammdf and nptdms log when a file ends before the data its blocks announce (a recording
#: cut off); the log record's text (its format string) is searched.
_CUT_SHORT = ("exceeds the file size", "outside the file size", "less data than expected", "metadata is incomplete",
              "not a multiple of the chunk size", "Cropping data")


class _Sink:
    """A stream that drops what is written (asammdf prints tracebacks and block dumps itself)."""

    def write(self, text: str) -> int:
        return len(text)

    def flush(self) -> None:
        pass


class _Kept(logging.Handler):
    """Log records of a library, kept from the console: the first that says the file is cut short."""

    def __init__(self):
        super().__init__(logging.DEBUG)
        self.cut_short: str | None = None

    def emit(self, record):
        if self.cut_short is None and any(k in str(record.msg) for k in _CUT_SHORT):
            with contextlib.suppress(Exception):
                self.cut_short = " ".join(record.getMessage().split())[:200]

    def handleError(self, record):  # a record that cannot be formatted: nothing to show
        pass


@contextlib.contextmanager
def _quiet_loggers(name: str, handler: logging.Handler):
    """During the block, the records of logger ``name`` and its children go to ``handler`` only."""
    top = logging.getLogger(name)
    loggers = [top] + [logging.getLogger(n) for n, lg in list(logging.root.manager.loggerDict.items())
                       if n.startswith(name + ".") and isinstance(lg, logging.Logger)]
    saved = [(lg, lg.handlers, lg.propagate) for lg in loggers]
    for lg in loggers:
        lg.handlers, lg.propagate = ([handler], False) if lg is top else ([], True)
    try:
        yield
    finally:
        for lg, handlers, propagate in saved:
            lg.handlers, lg.propagate = handlers, propagate


@contextlib.contextmanager
def library_call(kind: str, what: str, lib: str, path):
    """Run the block (calls into ``lib`` reading ``path``) behind the boundary of this module.

    Parameters
    ----------
    kind : str
        The format in the messages: ``"MDF"``, ``"TDMS"``.
    what : str
        What the file should be: ``"an MDF4 file"``, ``"a TDMS file"``.
    lib : str
        The package, also the name of its logger: ``"asammdf"``, ``"nptdms"``.
    path : str or os.PathLike
        The file read.

    Raises
    ------
    MeasuredDataError
        ``"KIND file 'PATH' is cut short: ... (lib: its record); export it again from the
        recorder"`` when a record says so (before any other error of the block, which may follow
        from it); ``"cannot read KIND file 'PATH': it is damaged, cut short or not WHAT (lib:
        what it said); export it again from the recorder"`` for any other exception of the block
        but a MeasuredDataError (passed on as it is); ``"...: not enough memory ..."``.
    """
    name = repr(str(path))
    kept = _Kept()
    failure = None
    with (_quiet_loggers(lib, kept), warnings.catch_warnings(), contextlib.redirect_stdout(_Sink()),
          contextlib.redirect_stderr(_Sink())):
        warnings.simplefilter("ignore")
        try:
            yield
        except BaseException as exc:
            close_half_made(exc)
            if not isinstance(exc, Exception) or (kept.cut_short is None and isinstance(exc, MeasuredDataError)):
                raise
            if isinstance(exc, MemoryError):
                failure = f"cannot read {kind} file {name}: not enough memory ({lib} ran out); free memory"
            else:
                failure = (f"cannot read {kind} file {name}: it is damaged, cut short or not {what} "
                           f"({lib}: {said(exc, path)}); export it again from the recorder")
    if kept.cut_short is not None:
        raise MeasuredDataError(f"{kind} file {name} is cut short: it ends before the data its blocks announce "
                                f"({lib}: {kept.cut_short}); export it again from the recorder")
    if failure is not None:
        raise MeasuredDataError(failure)


def said(exc: BaseException, path) -> str:
    """What a library's exception says, on one line, without the memory map or the path it names."""
    text = re.sub(r"'?<mmap\.mmap [^>]*>'?", "the file", " ".join(str(exc).split()))
    for p in {str(path), os.path.abspath(str(path))} - {""}:
        text = text.replace(f'"{p}"', "the file").replace(repr(p), "the file")
    text = text or type(exc).__name__
    return text if len(text) <= 160 else text[:157] + "..."


def close_half_made(exc: BaseException) -> None:
    """Close the asammdf objects whose construction ``exc`` interrupted.

    asammdf's ``MDF4.__init__``, when reading fails, deletes its ``_file`` attribute, which
    ``close()`` (called by ``__del__``) reads: collected later, such an object prints an
    AttributeError traceback ("Exception ignored in ...") after the refusal. Closed here with that
    attribute back, it removes what it made (a temporary copy of an unfinalised file) and its
    ``__del__`` finds it closed.
    """
    seen: set[int] = set()
    tb = exc.__traceback__
    while tb is not None:
        obj = tb.tb_frame.f_locals.get("self")
        tb = tb.tb_next
        if obj is None or id(obj) in seen or not type(obj).__module__.startswith("asammdf."):
            continue
        seen.add(id(obj))
        if not hasattr(type(obj), "__del__") or not hasattr(obj, "close"):
            continue
        with contextlib.suppress(Exception):
            for attr in ("_file", "_mapped_file", "_tempfile"):
                if not hasattr(obj, attr):
                    setattr(obj, attr, None)
            if not hasattr(obj, "_from_filelike"):
                obj._from_filelike = False
            obj.close()
        with contextlib.suppress(Exception):
            obj._closed = True  # close() returns at once when __del__ calls it
