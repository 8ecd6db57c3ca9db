"""The robot file: reading it (YAML 1.2 with lines, within limits), its schema and the
``optimize:`` section's, validation once into the :class:`~kingen.robot.model.Robot`,
parametric layouts, limb models and their registry (:mod:`kingen.robot.limbs`). Knows no
host: hosts register the checks of the names they make from a robot's name."""
