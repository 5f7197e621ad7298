"""From a tool library to safe spindle speeds: predicted joint with its uncertainty, tool-point FRF,
stability lobes with their 5/50/95 % limits and a probability-of-stability map, recommended operating
points, and an HTML report.

Data flow: ``campaign`` (models, subassembly) → ``stability`` (lobes) → ``recommend`` → ``cli``.
Design notes: ``docs/design/recommend.md``.
"""
