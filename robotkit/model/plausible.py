"""What a real part plausibly is: thresholds the build's warnings and check's lints share.

The build's warnings (robotkit.pipeline.buildwarn) and check's lints
(robotkit.check.lints) judge a robot by the same numbers, so they live here once.
Standard library only: the build warnings import this on every build, cheaply.
"""

DENSITY_RANGE = (10.0, 25000.0)
"""Plausible density of a part, kg/m^3: aerogel-ish foams to osmium."""

PART_SIZE_RANGE = (1e-4, 10.0)
"""Plausible extent of one part, m: larger is a mesh in millimetres read as metres, smaller the reverse."""
