"""kingen's 3D view of a robot: :func:`scene` (the robot at a pose as plain JSON data, with
optional overlays: frames, markers, arrows, ghost, surface, points; kingen.view.scene), and
:func:`page_html` (one self-contained HTML page of a scene) and :func:`view_fragment` (that page
as an ``<iframe srcdoc>`` for another report to hold; kingen.view.page)."""

from .page import page_html, view_fragment
from .scene import machine_at, scene

__all__ = ["machine_at", "page_html", "scene", "view_fragment"]
