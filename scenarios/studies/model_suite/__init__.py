"""The model correction measured on suites of cases and plant trucks.

:mod:`~rigsim.scenarios.studies.model_suite.plants`: the plant trucks of a case (the study's data,
:func:`rigsim.scenarios.studies.suites.model_plants`), their scenarios and runs;
:mod:`~rigsim.scenarios.studies.model_suite.report`: the tables and goals of the study's rows.
``benchmarks/model_correction.py`` runs the study; ``benchmarks/model_error.py`` reads its output.
"""
