"""The command line describes itself: `hdjoint --version`; every subcommand
has a description and examples in its help; and every option the README
shows on an `hdjoint <subcommand>` line exists in that subcommand's help."""
import re
from pathlib import Path

import pytest

import hdjoint
from hdjoint.app.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[2]


def subparsers(parser, path=()):
    """(command words, parser) of every subcommand, nested ones (fleet's) too."""
    for action in parser._actions:
        if action.__class__.__name__ == "_SubParsersAction":
            for name, sub in action.choices.items():
                yield (*path, name), sub
                yield from subparsers(sub, (*path, name))


def test_version(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"hdjoint {hdjoint.__version__}"


@pytest.mark.parametrize("words,parser", list(subparsers(build_parser())), ids=lambda x: " ".join(x)
                         if isinstance(x, tuple) else "")
def test_every_subcommand_has_a_description_and_an_example(words, parser):
    assert parser.description and len(parser.description) > 40
    examples = [line.strip() for line in (parser.epilog or "").splitlines()[1:]]
    assert examples and all(e.startswith("hdjoint " + " ".join(words)) for e in examples), parser.epilog
    for example in examples:  # each example parses
        argv = [w.strip('"') for w in example.split()[1:]]
        build_parser().parse_args(argv)


def readme_command_lines() -> list[str]:
    """Every `hdjoint ...` line in the README's code blocks, comments dropped."""
    text = (ROOT / "README.md").read_text()
    lines = []
    for block in re.findall(r"```\w*\n(.*?)```", text, re.S):
        for line in block.splitlines():
            line = line.split("  #", 1)[0].strip()
            if line.startswith("hdjoint "):
                lines.append(line)
    lines += re.findall(r"`(hdjoint [^`]+)`", text)
    return lines


def options_of(words) -> set[str]:
    parser = build_parser()
    for word in words:
        found = dict(subparsers(parser)).get((word,))
        if found is None:
            break
        parser = found
    return {o for a in parser._actions for o in a.option_strings}


def test_every_option_the_readme_names_exists():
    lines = readme_command_lines()
    assert len(lines) > 8
    missing = []
    for line in lines:
        words = line.split()[1:]
        sub = [w for w in words[:2] if not w.startswith("-")]
        known = options_of(sub[:2] if sub and sub[0] == "fleet" else sub[:1])
        missing += [f"{line}: {w}" for w in words if w.startswith("--") and w.split("=")[0] not in known]
    assert not missing, "\n".join(missing)


def test_the_check_sees_a_missing_option():
    assert "--split-gaps" in options_of(["estimate"]) and "--split-gaps" not in options_of(["diagnose"])
    assert "--engine" in options_of(["fleet", "estimate"])


def test_simulates_shortest_duration_is_the_apis():
    from hdjoint.api.functions import SHORTEST_SIMULATION
    from hdjoint.app import cli
    assert cli.SHORTEST_SIMULATION == SHORTEST_SIMULATION
