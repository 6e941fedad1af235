"""One finding of a check: severity, rule, subject, message, hint, and where it is."""

from __future__ import annotations

from dataclasses import dataclass


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
