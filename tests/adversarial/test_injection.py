"""Attacks by content and by name (issue 56): a recording or parameter
file that is a link to a file holding a secret never gets that secret into a
message (the error names the file, line and column, not what is in them);
a file name with a newline or a terminal escape is escaped in the one-line
message, never printed raw."""
from __future__ import annotations

import pytest

from hdjoint.io.outputs import printable

from cli_helpers import assert_one_line_error, rec_csv, run_cli, simulated  # noqa: F401 (fixtures)

MARKER = "S3CRET-MARKER-7f3a"

# What the linked-to file holds: the marker where a reader would quote it.
SECRET_FILES = {
    "first line": f"root:{MARKER}:19000:0:99999:7:::\nbin:*:19000\n",
    "a column name": f"time,i_m,theta_m,{MARKER}\n0,0,0,0\n",
    "a duplicate column name": f"time,i_m,theta_m,theta_l,{MARKER},{MARKER}\n0,0,0,0,0,0\n",
    "a cell": f"time,i_m,theta_m,theta_l\n0,0,0,0\n0.001,{MARKER},0,0\n",
    "a time": f"time,i_m,theta_m,theta_l\n0,0,0,0\n{MARKER},0,0,0\n",
    "a quoted cell": f'time,i_m,theta_m,theta_l\n0,0,0,0\n0.001,"{MARKER}\n",0,0\n',
    "a line too long": f"time,i_m,theta_m,theta_l\n{MARKER}" + "x" * 70000 + "\n",
    "JSON": f'{{"{MARKER}": 1}}\n',
    "a JSON value": f'{{"Kt": "{MARKER}"}}\n',
    "a JSON key given twice": f'{{"{MARKER}": 1, "{MARKER}": 2}}\n',
    "a tolerance": f'{{"tolerance": {{"{MARKER}": 0.1}}}}\n',
}


@pytest.mark.parametrize("content", SECRET_FILES, ids=str)
@pytest.mark.parametrize("as_what", ["recording", "parameter file", "diagnosed recording"])
def test_a_linked_secret_never_reaches_a_message(rec_csv, tmp_path, capsys, content, as_what):
    secret = tmp_path / "secret.txt"
    secret.write_text(SECRET_FILES[content])
    link = tmp_path / "evil.csv"
    link.symlink_to(secret)
    argv = {"recording": ("estimate", link, "-o", tmp_path / "e.csv"),
            "parameter file": ("estimate", rec_csv, "--params", link, "-o", tmp_path / "e.csv"),
            "diagnosed recording": ("diagnose", link, "--out", tmp_path / "d")}[as_what]
    code, out, err = run_cli(capsys, *argv)
    assert code == 2
    assert_one_line_error(err, str(link))
    assert MARKER not in out + err
    assert not (tmp_path / "e.csv").exists() and not (tmp_path / "d").exists()


NAMES = {"a newline": "rec\nhdjoint estimate: forged line.csv", "a terminal escape": "rec\x1b[2J\x1b]0;pwned\x07.csv",
         "a carriage return": "rec\r.csv", "a delete": "rec\x7f.csv"}


@pytest.mark.parametrize("name", NAMES, ids=str)
@pytest.mark.parametrize("where", ["missing recording", "malformed recording", "output"])
def test_a_name_with_control_characters_is_escaped(tmp_path, capsys, rec_csv, name, where):
    odd = tmp_path / NAMES[name]
    if where == "malformed recording":
        odd.write_text("not,a,recording\n1,2,3\n")
    argv = ("estimate", rec_csv, "-o", tmp_path / "no" / NAMES[name]) if where == "output" else \
        ("estimate", odd, "-o", tmp_path / "e.csv")
    code, _, err = run_cli(capsys, *argv)
    assert code == 2
    assert_one_line_error(err)
    assert not any(c in err.rstrip("\n") for c in "\n\r\x1b\x07\x7f"), repr(err)
    assert printable(NAMES[name]) in err  # escaped as repr would: \\n, \\x1b
