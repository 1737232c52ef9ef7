"""visland: a reference open pipeline for vision-based landing on unknown runways.

Core package (this folder): frames and rotations, camera, runway, scenarios, flight
simulation, sensors, ideal image features, file contracts and the command line. The stages
live in sibling subpackages: :mod:`visland.render`, :mod:`visland.detection`,
:mod:`visland.tracking`, :mod:`visland.estimation` and :mod:`visland.datasets`.
"""
__version__ = "0.1.0"
