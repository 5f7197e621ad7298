"""Experimental campaign: many tools on one spindle–holder, identified joints, ANFIS, predictions.

Modules: :mod:`.config` (campaign folder → typed objects), :mod:`.synth`
(a synthetic campaign with a documented truth law), :mod:`.run` (identify every
measurement, resumable, process pool or Dask), :mod:`.results` (the
``identified.csv`` schema, reader and writer), :mod:`.learn` (ANFIS per target
and baselines), :mod:`.predict` (joint and FRF of a tool never measured).
Design notes and measurements: ``docs/design/campaign.md``.
"""
