"""The fleet's inputs: recordings from glob patterns, and the params map that
says which parameter file (and joint id) belongs to each recording.

The map is a JSON object from glob patterns, relative to the map file's
folder, to parameter files (also relative to it); the first pattern that
matches a recording wins. `*` and `?` stay within one folder, `**` spans
folders. The joint id is the matched pattern, unless a regex given with
--joint-pattern (named groups `joint` and, optionally, `date`) matches the
recording's path relative to the map's folder.
"""
from __future__ import annotations

import glob
import hashlib
import json
import os
import re
import sys
from dataclasses import dataclass, replace
from datetime import datetime, timezone
from pathlib import Path

from hdjoint.io.outputs import printable
from hdjoint.jobs.inputs import UserError


@dataclass(frozen=True)
class Job:
    """One recording to process."""
    recording: str      # absolute path
    params: str | None  # absolute path of its parameter file (None: the defaults)
    joint: str          # as matched: the map's pattern, or the joint group of --joint-pattern
    date: str           # ISO date (or date-time) the trend is ordered by
    name: str           # folder name of its outputs under DIR/<folder>/

    @property
    def folder(self) -> str:
        """The joint id as a relative folder: each part of it made a safe name."""
        return "/".join(filter(None, (_safe(part) for part in self.joint.split("/")))) or "_"


def glob_to_regex(pattern: str) -> re.Pattern:
    """A glob pattern as an anchored regex over '/'-separated relative paths."""
    out, i = [], 0
    while i < len(pattern):
        c = pattern[i]
        if pattern.startswith("**/", i):
            out.append("(?:.*/)?")
            i += 3
            continue
        if pattern.startswith("**", i):
            out.append(".*")
            i += 2
            continue
        if c == "*":
            out.append("[^/]*")
        elif c == "?":
            out.append("[^/]")
        elif c == "[":
            end = pattern.find("]", i + 1)
            if end < 0:
                raise UserError(f"glob pattern '{pattern}': unclosed '['")
            body = pattern[i + 1:end]
            out.append("[" + ("^" + body[1:] if body.startswith("!") else body) + "]")
            i = end + 1
            continue
        else:
            out.append(re.escape(c))
        i += 1
    return re.compile("".join(out) + r"\Z")


@dataclass(frozen=True)
class ParamsMap:
    folder: Path
    entries: tuple[tuple[str, re.Pattern, Path], ...]  # (pattern, compiled, parameter file)

    def match(self, recording: Path) -> tuple[str, Path] | None:
        try:
            rel = recording.resolve().relative_to(self.folder).as_posix()
        except ValueError:
            return None
        for pattern, regex, params in self.entries:
            if regex.match(rel):
                return pattern, params
        return None


def read_params_map(path: str | os.PathLike) -> ParamsMap:
    from hdjoint.io.parameters import MAX_FILE_BYTES, read_small_file
    path = Path(path)
    try:
        text = read_small_file(path)
        if text is None:
            raise UserError(f"{printable(path)}: larger than {MAX_FILE_BYTES // 1024} kB; a params map is a small "
                            "JSON object (is this a params map?)")
        data = json.loads(text)
    except OSError as e:
        raise UserError(f"{printable(path)}: cannot read the params map ({e.strerror})") from None
    except UnicodeDecodeError as e:
        raise UserError(f"{printable(path)}: not UTF-8 text ({e.reason} at byte {e.start})") from None
    except json.JSONDecodeError as e:
        raise UserError(f"{path}: line {e.lineno}, column {e.colno}: not valid JSON ({e.msg})") from None
    if not isinstance(data, dict) or not data:
        raise UserError(f"{path}: the params map must be a non-empty JSON object "
                        '{"glob pattern": "parameter file", ...}')
    folder = path.resolve().parent
    entries = []
    for pattern, params in data.items():
        if not isinstance(params, str):
            raise UserError(f"{path}: pattern '{pattern}' must map to a parameter file path, not {params!r}")
        file = (folder / params).resolve()
        if not file.is_file():
            raise UserError(f"{path}: pattern '{pattern}': parameter file {params} not found (in {folder})")
        entries.append((pattern, glob_to_regex(pattern), file))
    return ParamsMap(folder, tuple(entries))


def find_recordings(patterns: list[str], exclude: Path | None = None) -> list[Path]:
    """The files PATTERNS match, never one under EXCLUDE (the fleet's own
    output folder: its estimates.csv files are not recordings)."""
    found = []
    for pattern in patterns:
        hits = sorted(glob.glob(pattern, recursive=True)) if glob.has_magic(pattern) else [pattern]
        found += [Path(h).resolve() for h in hits if Path(h).is_file()]
    unique = list(dict.fromkeys(found))
    if exclude is not None:
        exclude = Path(exclude).resolve()
        unique = [p for p in unique if not p.is_relative_to(exclude)]
    if not unique:
        outside = f" outside --out {exclude}" if exclude is not None else ""
        raise UserError(f"no recordings match {' '.join(patterns)}{outside}")
    return unique


def _safe(name: str) -> str:
    """A name as one folder name: glob characters dropped, other odd ones made '_'."""
    return re.sub(r"[^A-Za-z0-9._=-]+", "_", re.sub(r"[*?\[\]!]", "", name)).strip("._")


def _mtime_date(path: Path) -> str:
    return datetime.fromtimestamp(path.stat().st_mtime, timezone.utc).strftime("%Y-%m-%dT%H:%M:%S")


def plan(patterns: list[str], params_map: str | None, joint_pattern: str | None,
         out: str | os.PathLike | None = None) -> list[Job]:
    """The jobs for every recording (none under OUT, the fleet's outputs): its
    parameter file, joint id and date. A recording no map pattern matches is
    a user error (named); a map pattern that matches none is warned about."""
    recordings = find_recordings(patterns, exclude=out)
    pmap = read_params_map(params_map) if params_map else None
    regex = None
    if joint_pattern:
        try:
            regex = re.compile(joint_pattern)
        except re.error as e:
            raise UserError(f"--joint-pattern: not a valid regex ({e})") from None
        if "joint" not in regex.groupindex:
            raise UserError("--joint-pattern: the regex needs a named group (?P<joint>...)")
    base = pmap.folder if pmap else Path.cwd().resolve()
    jobs, names = [], set()
    for rec in recordings:
        params, joint = None, rec.parent.name
        if pmap:
            hit = pmap.match(rec)
            if hit is None:
                raise UserError(f"{rec}: no pattern of the params map matches it")
            joint, params = hit
        date = None
        if regex:
            rel = rec.relative_to(base).as_posix() if rec.is_relative_to(base) else rec.as_posix()
            m = regex.search(rel)
            if m is None:
                raise UserError(f"{rec}: --joint-pattern does not match '{rel}'")
            joint = m.group("joint")
            date = m.groupdict().get("date")
        job = Job(str(rec), str(params) if params else None, joint, date or _mtime_date(rec), _safe(rec.stem) or "_")
        if (job.folder, job.name) in names:
            job = replace(job, name=f"{job.name}-{hashlib.sha256(job.recording.encode()).hexdigest()[:8]}")
        names.add((job.folder, job.name))
        jobs.append(job)
    if pmap:
        used = {pmap.match(rec)[0] for rec in recordings}
        for pattern, _, _ in pmap.entries:
            if pattern not in used:
                print(f"warning: {printable(params_map)}: pattern '{pattern}' is used for none of the recordings",
                      file=sys.stderr)
    return jobs
