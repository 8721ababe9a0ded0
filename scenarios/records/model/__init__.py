"""Output correction by a rig-calibrated truck model: F_corr = F_model(x_ref) + L(W(F_rig - F_model(x_a))).

* :mod:`.model_runs`: :func:`~.model_runs.model_forces`, the truck model's tire forces with its pans
  following a measured motion (x_ref or x_a, 1 kHz);
* :mod:`.first_guess`: the first guess (payload from the static loads, a catalogue for the rest);
* :mod:`.calibrate`: :func:`~.calibrate.calibrate`, the uncertain truck parameters fitted so the
  model, pans following x_a, reproduces F_rig (rig signals only), weighted by :mod:`.weighting`
  towards the frequencies the correction uses the model at;
* :mod:`.cab_choice`: :func:`~.cab_choice.calibrate_cab`, the cab held, fitted, or (default) both
  calibrated and the clearly better fit kept;
* :mod:`.frame_choice`: :func:`~.frame_choice.calibrate_truck`, the cab chosen, then a described
  truck's frame, engine on mounts and digressive dampers each left out or, where clearly better, fitted;
* :mod:`.restart`: :func:`~.restart.calibrate_again`, a fit refused for its model error searched
  again from the leaf springs sliding and with each axle's stations held alike, the best kept;
* :mod:`.differential`: :func:`~.differential.correct_with_model` (calibrate, check, correct with
  the linear correction L of the model's residual, or fall back to L on the wheels the model does
  not reproduce, with one sentence why) and the differential form
  :func:`~.differential.differential_correction`;
* :mod:`.result`: :class:`~.result.Calibration`, :class:`~.result.ModelCorrection`.

Kept empty of imports: a command's parser may import the package without loading numpy or MuJoCo.
"""
