"""Tools for checking another implementation (a C++/GPU port) against clothsim.

:mod:`~clothsim.ports.formats` reads and writes trajectories in every format,
:mod:`~clothsim.ports.export` writes everything a port needs, :mod:`~clothsim.ports.compare`
compares trajectories and matrices, :mod:`~clothsim.ports.check` checks a port one step at a
time, :mod:`~clothsim.ports.diff` compares two models and :mod:`~clothsim.ports.conformance`
writes the conformance set. See docs/ports.md.
"""
