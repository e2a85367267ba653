"""Benchmark figures, printed and written to docs/results/NAME.md with the
stamp.py line (generated: never typed by hand)."""
from __future__ import annotations

from pathlib import Path

import stamp

RESULTS_DIR = Path(__file__).resolve().parents[1] / "docs" / "results"


class ResultsPage:
    """Lines that a benchmark prints as it goes, kept for its results page."""

    def __init__(self, name: str, title: str, command: str):
        self.path = RESULTS_DIR / f"{name}.md"
        self.lines = [f"# {title}", "",
                      stamp.generated_by(command), ""]

    def say(self, line: str = "") -> None:
        print(line, flush=True)
        self.lines.append(line)
        if not line.startswith("|"):
            self.lines.append("")  # a paragraph each in Markdown; table rows stay together

    def write(self) -> Path:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.path.write_text("\n".join(self.lines).rstrip() + "\n")
        print(f"wrote {self.path}")
        return self.path
