"""What follows from the geometry: the numpy reference (every posture of every pose),
force lines and the direct index with its proven lower bound, forward kinematics and every
assembly mode, posture switches, clearance models, the seeded poses of a verification
region, and what any host's routine answers (:mod:`kingen.kinematics.routine`)."""
