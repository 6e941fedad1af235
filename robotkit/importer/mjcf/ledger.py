"""The ledger: one line per element of the MJCF that does not reach a target format unchanged:
where it is (file:line), what it is, which formats, what happened (dropped, approximated how)."""

from __future__ import annotations

from dataclasses import dataclass, field

from robotkit.importer.recipe_writer import wrap


@dataclass(frozen=True)
class Entry:
    where: str
    element: str
    formats: str  # "all", or the formats that lose it ("URDF, SDF")
    what: str

    def __str__(self) -> str:
        return f"{self.where}: {self.element}: {self.formats}: {self.what}"


@dataclass
class Ledger:
    entries: list[Entry] = field(default_factory=list)

    def add(self, where: str, element: str, formats: str, what: str) -> None:
        self.entries.append(Entry(where, element, formats, what))

    def lines(self) -> list[str]:
        return [str(e) for e in self.entries]

    def __len__(self) -> int:
        return len(self.entries)

    def block(self) -> list[str]:
        """The ledger as the recipe's header says it (one entry per line, wrapped)."""
        if not self.entries:
            return ["ledger: nothing of the original is lost"]
        lines = [f"ledger: {len(self)} element{'s' if len(self) > 1 else ''} of the original not carried "
                 "unchanged (where: element: formats: what happened)"]
        for line in self.lines():
            lines.extend("  " + part for part in wrap(line, 110))
        return lines
