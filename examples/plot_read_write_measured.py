"""
Reading and writing measured files
==================================

One reader, :func:`rigsim.correction.io.measured.read_channels`, reads every file a lab keeps into SI
channels on a uniform time axis; one writer, :func:`rigsim.correction.io.measured.write_channels`,
writes them in the format of the file's extension. Here a text file in a Swiss locale
(apostrophe thousands separator, forces in N, LVDT in mm) is read, written as MTS RPC III (int16) and as CSV,
and read back.
"""

import pathlib
import tempfile

import numpy as np

from rigsim.correction.io.measured import read_channels, write_channels

folder = pathlib.Path(tempfile.mkdtemp())
t = np.arange(2000) / 500.0
force_kN = 21.9885 + 1.5 * np.sin(2 * np.pi * 10.0 * t)
lvdt_mm = 4.0 * np.sin(2 * np.pi * 1.5 * t)
src = folder / "lab.txt"
lines = ["# operator: example", "time [s]\tFz_FL [N]\tLVDT_FL [mm]"]
lines += [f"{a:.3f}\t{b * 1000:,.1f}\t{c:.4f}".replace(",", "'") for a, b, c in zip(t, force_kN, lvdt_mm)]
src.write_text("\n".join(lines) + "\n", encoding="utf-8")
print("\n".join(lines[:4]))

# %%
# The force column is written in N with apostrophes (``21'988.5``), the LVDT in mm;
# the reader takes the decimal mark and the separator from the numbers and the unit from the
# header, and returns SI.

c = read_channels(src)
print(c.format, c.names, dict(c.units), dict(c.source_units), f"{c.fs_hz:g} Hz")
print("metadata:", dict(c.metadata))

# %%
# Written as RPC III and as CSV, and read back: RPC III stores int16 with a scale per channel,
# so it comes back to within half a quantization step.

rsp = write_channels(folder / "lab.rsp", c, metadata={"operator": "example"})
csv = write_channels(folder / "lab.csv", c)
for path in (rsp, csv):
    back = read_channels(path)
    err = max(np.max(np.abs(back.data[n] - c.data[n])) for n in c.names)
    print(path.suffix, back.format, back.names, f"largest difference {err:.3g} (SI units)")
