"""One finding of a check: severity, rule, subject, message, hint, and where it is."""

from __future__ import annotations

from dataclasses import dataclass

from robotkit.errors import display_path

SEVERITIES = ("error", "warning")
STAGES = ("check_urdf", "ign sdf -k", "mujoco", "equivalence", "consumer", "consumers", "simulation", "build",
          "input", "motion", "self-collision")
"""The checks that are stages; every other rule is a physics lint (robotkit.check.lints)."""
EQUIVALENCE_CONFIGS = 100
"""The configurations at which the equivalence stage compares URDF, model.sdf and MJCF."""


@dataclass(frozen=True)
class Finding:
    severity: str  # error | warning
    check: str  # rule name, e.g. "implied-density"
    subject: str  # "link 'base'", "joint 'j1'", a file or the robot
    message: str
    hint: str = ""
    file: str | None = None
    line: int | None = None

    def __str__(self) -> str:
        hint = f" (hint: {self.hint})" if self.hint else ""
        return f"{self.severity}: {self.subject}: {self.message}{hint} [{self.check}]"

    def fails(self, fail_on: str = "error") -> bool:
        """Whether this finding makes the check fail (exit 1) at ``--fail-on fail_on``."""
        return SEVERITIES.index(self.severity) <= SEVERITIES.index(fail_on)


def input_findings(problems, source: str) -> list[Finding]:
    """The problems of input that could not be checked (a recipe that does not load, a
    file that does not exist) as findings, so CI formats report them too (check ``input``)."""
    return [Finding("error", "input", p.key or (p.file and _display(p.file)) or source, p.message,
                    file=p.file, line=p.line) for p in problems]


def _display(path: str) -> str:
    return display_path(path)
