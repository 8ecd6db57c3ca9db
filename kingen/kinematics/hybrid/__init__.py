"""The hybrid kinematics: a constrained machine's parasitic motion in closed form
(:mod:`.parasitic`, with :mod:`.parasitic_axes` for platform-fixed axes and
:mod:`.parasitic_tube` for a passive tube), and a serial wrist on a parallel part (:mod:`.wrist`:
the inverse; :mod:`.wrist_forward`, :mod:`.wrist_rates`, :mod:`.wrist_loads`: its forward, joint
rates and loads)."""
