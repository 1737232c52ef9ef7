"""Test support shared by several test folders, imported explicitly (``from tests.helpers.X import ...``).

- :mod:`tests.helpers.raycast_airport`: a painted airport ray-cast pixel by pixel (no OpenGL),
  for the detection tests and ``benchmarks/raycast_approach.py``.
- :mod:`tests.helpers.detection_frames`: cached ray-cast frames along flown approaches with their
  exact labels.
- :mod:`tests.helpers.estimation_sims`: simulated approaches and prepared observer inputs,
  computed once per session.
- :mod:`tests.helpers.chessboard_views`: chessboard photographs through a known lens (calibration).
- :mod:`tests.helpers.cockpit_frames`: a synthetic cockpit sequence with known structure pixels
  (structure mask).

Nothing here ships in the ``visland`` distribution. The repository root is put on ``sys.path``
by pytest (``pythonpath`` in pyproject.toml).
"""
