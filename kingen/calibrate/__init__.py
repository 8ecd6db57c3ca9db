"""Kinematic calibration: the machine as built, identified from measurements.

``measurements.py`` (the CSV), ``parameters.py`` (the parameter vector and its groups),
``prediction.py`` (what a parameter vector predicts), ``alignment.py`` (the measuring frame's first
estimate, the input checks), ``noise.py`` (the noise model, covariances, outliers),
``identification.py`` (generalised least squares),
``identifiability.py`` (rank, combinations, indices), ``plan.py`` (D-optimal poses),
``report.py`` (calibration.json, report.html) and ``output.py`` (the calibrated robot file).
"""
