"""``rigsim programme``: a lab's test programme, many records of a truck corrected by its model,
calibrated once per truck configuration and reused, on the local pool or a Dask cluster.

:mod:`.settings` reads the inputs (files, folders, globs, or a programme file) and checks them
before any work; :mod:`.run` calibrates each truck on its first records and corrects the others
with that calibration, in parallel, resumable; :mod:`.report` writes the programme's report
(Markdown, JSON, a figure); :mod:`.command` is the command's parser and printing.
"""
