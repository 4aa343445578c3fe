"""The README's Python examples run as written, from the top of the repository."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

from support.readme import missing, shown_commands

ROOT = Path(__file__).resolve().parents[1]


def test_readme_python_blocks_run_and_print_what_their_comments_say(monkeypatch, capsys):
    blocks = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
    assert blocks
    monkeypatch.chdir(ROOT)
    for code in blocks:
        exec(compile(code, "README.md", "exec"), {})
        printed = capsys.readouterr().out.splitlines()
        promised = [line.split("# ", 1)[1].strip() for line in code.splitlines()
                    if line.startswith("print(") and "# " in line]
        # A comment that gives the printed values ("8 True") must be what the line printed; others
        # ("why S4 is not S0") describe it.
        for out, said in zip(printed, promised):
            if re.fullmatch(r"\d[\w. ]*", said):
                assert out == said, (out, said)


def _runs(args):
    """The README's commands but the two that tests run anyway and check there: the whole Killian log
    (its slow test) and Taylor Hall's (the demo runs it, in the installed wheel's test)."""
    return "killian" not in args and "taylor_hall" not in args


@pytest.mark.parametrize("args, shown", [c for c in shown_commands() if _runs(c[0])],
                         ids=lambda v: " ".join(v)[:40] if isinstance(v, list) else "")
def test_the_readme_shows_what_its_commands_print(tmp_path, args, shown):
    """Run from the top of the repository as the README says (its output folders moved to a temporary
    one): every line it shows is printed, in order."""
    args = [str(tmp_path / a) if a.startswith("out/") else a for a in args]
    run = subprocess.run([sys.executable, "-m", "bootmap.cli", *args], capture_output=True, text=True, cwd=ROOT,
                         timeout=300)
    printed = run.stdout.replace(str(tmp_path) + "/", "")
    assert missing(shown, printed) == [], printed[-3000:]


def test_every_command_the_readme_shows_output_for_is_checked():
    commands = [" ".join(a) for a, _ in shown_commands()]
    assert len(commands) >= 4 and any("killian" in c for c in commands)
