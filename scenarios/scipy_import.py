"""Import scipy.signal without re-parsing ~800 docstrings: 0.7 s off every process's start.

SciPy 1.17's ``xp_capabilities`` decorator (``scipy._lib._array_api``) parses the docstring of
every function it decorates with ``FunctionDoc`` when ``scipy.signal`` is imported, to append a
note on array-API backends: measured here, 0.7 of the 0.79 s that ``import scipy.signal`` takes,
in every rigsim process (the command and each worker), a third of a short run's fixed cost.

:func:`install` adds an import hook that, when ``scipy._lib._array_api`` is loaded, replaces the
``FunctionDoc`` it uses by :class:`_KeepDoc`, which leaves each docstring as it is (without that
note). Nothing else of SciPy changes: the functions are the same objects. The hook does nothing
when the module has no ``FunctionDoc`` (other SciPy versions), when SciPy was imported before
rigsim, or when ``RIGSIM_SCIPY_DOCS=1`` is set (full docstrings, as SciPy makes them).

The same hook defers ``scipy.stats``: ``scipy.signal``'s one use of it is ``_peak_finding``'s
``from scipy.stats import scoreatpercentile`` (for ``find_peaks_cwt``), which imports all of
``scipy.stats`` (measured: 0.27 s and ~25 MB of every run's start, where nothing uses it). While
that module loads, ``scipy.stats`` is a stand-in holding :func:`_scoreatpercentile`, which imports
the real function on its first call; the stand-in is removed right after, so ``import scipy.stats``
anywhere later loads SciPy's own. ``RIGSIM_SCIPY_DOCS=1`` turns this off too.
"""

from __future__ import annotations

import importlib.abc
import os
import sys
import types

__all__ = ["install", "TARGET", "STATS_USER"]

#: The module whose docstring parser is replaced.
TARGET = "scipy._lib._array_api"
#: The module of scipy.signal that imports scipy.stats, which is deferred while it loads.
STATS_USER = "scipy.signal._peak_finding"


class _KeepDoc:
    """Stands in for ``FunctionDoc`` in ``xp_capabilities``: the decorator appends to
    ``doc['Notes']`` and then keeps ``str(doc)`` after its first line (the signature)."""

    def __init__(self, func) -> None:
        self._doc = getattr(func, "__doc__", None) or ""
        self._sections: dict[str, list] = {}

    def __getitem__(self, key: str) -> list:
        return self._sections.setdefault(key, [])

    def __str__(self) -> str:
        return "\n" + self._doc


class _Loader(importlib.abc.Loader):
    def __init__(self, loader, name: str) -> None:
        self.loader, self.name = loader, name

    def create_module(self, spec):
        return self.loader.create_module(spec)

    def exec_module(self, module) -> None:
        if self.name == STATS_USER:
            _exec_without_stats(self.loader, module)
            return
        self.loader.exec_module(module)
        if hasattr(module, "FunctionDoc"):
            module.FunctionDoc = _KeepDoc


def _scoreatpercentile(*args, **kwargs):
    """``scipy.stats.scoreatpercentile``, imported on the first call (see the module's docstring)."""
    from scipy.stats import scoreatpercentile

    return scoreatpercentile(*args, **kwargs)


def _exec_without_stats(loader, module) -> None:
    if "scipy.stats" in sys.modules:
        loader.exec_module(module)
        return
    stand_in = types.ModuleType("scipy.stats", "stands in for scipy.stats while scipy.signal loads")
    stand_in.scoreatpercentile = _scoreatpercentile
    sys.modules["scipy.stats"] = stand_in
    try:
        loader.exec_module(module)
    finally:
        if sys.modules.get("scipy.stats") is stand_in:
            del sys.modules["scipy.stats"]


class _Finder(importlib.abc.MetaPathFinder):
    def __init__(self) -> None:
        self.waiting = {TARGET, STATS_USER}

    def find_spec(self, name, path, target=None):
        if name not in self.waiting:
            return None
        import importlib.util

        self.waiting.discard(name)  # so that the lookup below passes this finder by
        if not self.waiting:
            sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        if spec is not None and spec.loader is not None:
            spec.loader = _Loader(spec.loader, name)
        return spec


def install() -> bool:
    """Install the hook (once per process); returns whether it is active."""
    if os.environ.get("RIGSIM_SCIPY_DOCS") == "1" or TARGET in sys.modules:
        return False
    if not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.insert(0, _Finder())
    return True
