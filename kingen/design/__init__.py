"""Whether and how well the machine works: tilt limits, sweeps and slices
(:mod:`kingen.design.analysis`) and their figures, the robot file's design problem, the
swarm search and its checkpoint, the compiled tilt judge, and the optimisation report."""
