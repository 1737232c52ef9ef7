"""visland.estimation: the observers and filters of the seeds, their inputs, deviations and metrics.

Modules (one idea each):

- ``base``: the interface every observer shares (ObserverInput, Estimate, Observer, parameters)
  and the bad-input policy (errors for programming mistakes, coasting for missing measurements).
- ``inputs``: telemetry + image measurements -> one ObserverInput per step (d_F heading, runway
  heading as a filtered constant, velocities in the runway frame, virtual-frame corners 3.23,
  lines and the runway-plane normal 3.33).
- ``points``: two-point observers (thesis 4.2.1, 4.3.1, 4.4.2): oj-2p, ii-2p, cccs-2p,
  ccpi-hg-2p, ccpi-hosm-2p, cccj-2p. ``kalman``: kf-2p (annex, filterpy).
- ``lines``, ``lines_model``: two-line observers (thesis 4.2.2, 4.3.2, 4.4.3, annex).
- ``ecc``: the ECC'15 observers on z = (y1, y2, y3, 1/dH): ecc-hg, ecc-hosm.
- ``single_point``: the seed 001 single-point observer and its academic example.
- ``deviations``: from 1/dH to dX, dY and the runway width. ``metrics``: the seeds' metrics.
- ``registry``: SPEC observer names -> classes. ``runner``: one observer over prepared inputs.
- ``command``, ``study``, ``bench``, ``cli``: ``visland estimate``, ``visland study``,
  ``visland bench estimate``. ``thesis_tables``: the thesis figures the studies compare with.
- ``tuning``: gain helpers (second-order response time, Levant coefficients).

Nothing heavy is imported here: the CLI imports these modules inside its commands.
"""
