"""The manual stays a manual: hand-written docs/*.md at most 60 KB in all,
the README at most 8 KB, and every relative Markdown link in README.md and
docs/*.md points to a file (and heading) that exists. Measurements belong in
docs/results/, written by the benchmarks, which is not counted here."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
README = ROOT / "README.md"
KB = 1024  # bytes, as file sizes are usually given
DOCS_LIMIT = 60 * KB  # docs/*.md together (docs/results/ excluded)
README_LIMIT = 8 * KB

FENCE = re.compile(r"^(```|~~~).*?^\1", re.S | re.M)
CODE_SPAN = re.compile(r"(`+)(?!`).+?(?<!`)\1", re.S)
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
HEADING = re.compile(r"^#{1,6}\s+(.*?)\s*#*\s*$", re.M)
ANCHOR = re.compile(r"<a\s+(?:id|name)=\"([^\"]+)\"", re.I)


def hand_written() -> list[Path]:
    return sorted(DOCS.glob("*.md"))


def pages() -> list[Path]:
    return [README] + hand_written()


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"`|\*\*|__", "", heading).strip().lower()
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    text = FENCE.sub("", page.read_text(encoding="utf-8"))
    seen: dict[str, int] = {}
    out = set(ANCHOR.findall(text))
    for heading in HEADING.findall(text):
        base = slug(heading)
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.add(base if n == 0 else f"{base}-{n}")
    return out


def links(page: Path) -> list[str]:
    text = FENCE.sub("", page.read_text(encoding="utf-8"))
    text = CODE_SPAN.sub("", text)
    return LINK.findall(text)


def broken(page: Path) -> list[str]:
    problems = []
    for target in links(page):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):  # http:, https:, mailto:
            continue
        path, _, fragment = target.partition("#")
        path = path.split("?")[0]
        dest = (page.parent / path).resolve() if path else page
        try:
            dest.relative_to(ROOT)
        except ValueError:  # outside the repository (e.g. ../shared): not ours to check
            continue
        if not dest.exists():
            problems.append(f"{page.relative_to(ROOT)}: {target} (no such file)")
        elif fragment and dest.suffix == ".md" and fragment not in anchors(dest):
            problems.append(f"{page.relative_to(ROOT)}: {target} (no such heading)")
    return problems


def test_hand_written_docs_stay_under_60_kb():
    sizes = {p.name: p.stat().st_size for p in hand_written()}
    assert sum(sizes.values()) <= DOCS_LIMIT, (
        f"docs/*.md hold {sum(sizes.values())} bytes (limit {DOCS_LIMIT}): {sizes}; "
        "say how things work now, and leave measurements to docs/results/")


def test_readme_stays_under_8_kb():
    size = README.stat().st_size
    assert size <= README_LIMIT, f"README.md is {size} bytes (limit {README_LIMIT})"


@pytest.mark.parametrize("page", pages(), ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_point_to_existing_files(page):
    assert broken(page) == []


def test_the_link_check_sees_a_missing_file_and_heading(tmp_path, monkeypatch):
    monkeypatch.setattr(__import__(__name__), "ROOT", tmp_path)
    (tmp_path / "there.md").write_text("# A `heading`, here\n")
    page = tmp_path / "page.md"
    page.write_text("[ok](there.md#a-heading-here) [gone](gone.md) ![fig](x.png) "
                    "[bad](there.md#nope) `[code](not-a-link.md)` [web](https://example.org)\n")
    assert broken(page) == ["page.md: gone.md (no such file)", "page.md: x.png (no such file)",
                            "page.md: there.md#nope (no such heading)"]
