"""Correcting a record and identifying its actuators load neither python-control nor matplotlib
(python-control imports matplotlib's pyplot; a lab's script, a worker process or a command that
draws nothing should not pay for it): both are imported where a ``control.TransferFunction`` is
made or a figure drawn. Checked in a fresh interpreter, where ``sys.modules`` starts empty."""

from __future__ import annotations

import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]

_CODE = """
import sys
import numpy as np
from rigsim.correction.identification.actuator_fit import fit_actuator
from rigsim.correction.output.pipeline import correct_forces
from rigsim.correction.output.transfer import is_transfer_function

fs = 1000.0
rng = np.random.default_rng(3)
drive = rng.standard_normal((40_000, 1)) * 1e-3
# a second-order actuator, 12 Hz, damping 0.6 (discretised by the bilinear transform)
from scipy import signal
b, a = signal.bilinear([(2 * np.pi * 12) ** 2], [1, 2 * 0.6 * 2 * np.pi * 12, (2 * np.pi * 12) ** 2], fs)
pan = signal.lfilter(b, a, drive, axis=0)
fit = fit_actuator(drive[:, 0], pan[:, 0], fs)
force = 3e4 + 1e3 * rng.standard_normal((20_000, 1))
out = correct_forces(force, fit, fs)
assert np.all(np.isfinite(out.corrected_N)) and not is_transfer_function(fit.as_tf())
# -3 dB bandwidth of a second-order system (analytic): f_n sqrt(1 - 2 z^2 + sqrt((1 - 2 z^2)^2 + 1))
z = 0.6
f3 = 12.0 * np.sqrt(1 - 2 * z**2 + np.sqrt((1 - 2 * z**2) ** 2 + 1))
assert abs(fit.bandwidth_hz / f3 - 1) < 0.03, (fit.bandwidth_hz, f3)
print(sorted(m for m in ("control", "matplotlib") if m in sys.modules))
"""


def _loaded(code: str) -> str:
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout.strip().splitlines()[-1]


def test_identifying_and_correcting_load_neither_control_nor_matplotlib():
    assert _loaded(_CODE) == "[]"


def test_a_control_transfer_function_is_still_recognised():  # the probe above can fail
    code = ("import control\nfrom rigsim.correction.output.transfer import is_transfer_function\n"
            "print(is_transfer_function(control.tf([1.0], [1.0, 1.0])), is_transfer_function(([1.0], [1.0, 1.0])))")
    assert _loaded(code) == "True False"
