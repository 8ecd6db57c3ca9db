"""Will a program run? A G-code program (through LinuxCNC's own interpreter) or a CSV of poses
checked along its whole path on a robot: reach, joint travel, singular bands, the direct
index, assembly-mode changes, joint speeds and accelerations (``kingen check-path``).

Modules: :mod:`.moves` (what a program is made of), :mod:`.program` (moves from a CSV),
:mod:`.interpreter` and the canon script :mod:`.linuxcnc_canon` (moves from G-code),
:mod:`.sampling` (the path between the points), :mod:`.limits` (robot file and LinuxCNC
.ini), :mod:`.evaluation` (the decision quantities), :mod:`.refinement` (samples between
samples), :mod:`.timing` (a move timed on its own; joint rates), :mod:`.planner` with :mod:`.blends`
(G-code timed as LinuxCNC's trajectory planner moves it), :mod:`.judging` (a batch's samples
judged), :mod:`.findings` (what was found, in constant memory), :mod:`.check` (the whole
program, in batches), :mod:`.report` and :mod:`.page` (text, JSON, CSV, HTML).
"""
