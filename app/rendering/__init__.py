"""Rendering a compiled scene: the progressive renderer (renderer.py), launches sized to a
time budget (launches.py), one render on several devices (multidevice.py) or a Ray cluster
(farm.py), and what bidirectional path tracing takes of a scene (bdpt.py)."""
