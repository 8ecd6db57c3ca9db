"""Martyushev's forward kinematics of the general Stewart-Gough platform by elimination
templates: all 40 complex solutions (README.md here: source, licence, changes)."""

from .solver66 import solver66

__all__ = ["solver66"]
