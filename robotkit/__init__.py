"""robotkit: a declarative build system for robot description assets."""

__version__ = "0.1.0"
