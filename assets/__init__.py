"""MJCF models shipped with reform-sim: a person and the Directions Robot.

The files are package data; find them through ``sim.assets`` (``asset_xml``, ``asset_path``),
never by a path relative to the source tree, so that a non-editable install works too.
"""
