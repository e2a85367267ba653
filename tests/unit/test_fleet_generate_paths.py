"""`hdjoint fleet generate DIR` names the files where it wrote them: each
progress line is a path that exists (it printed DIR's logs/robot1/... relative
to DIR, so `generate logs` showed logs/robot1/... for logs/logs/robot1/...),
and the command it suggests finds them."""
import glob
import re

from cli_helpers import run_cli


def test_generate_prints_the_paths_it_wrote(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(capsys, "fleet", "generate", "logs", "--joints", "1", "--days", "2", "--duration", "0.5")
    assert code == 0, err
    printed = [line.split("] ", 1)[1] for line in err.splitlines() if line.startswith("[generate] ")]
    written = sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*.csv"))
    assert sorted(printed) == written and len(written) == 2
    assert all(p.startswith("logs/logs/robot1/j1/") for p in written)
    suggested = re.search(r"fleet diagnose '([^']+)'", out).group(1)
    assert sorted(glob.glob(suggested, recursive=True)) == written
