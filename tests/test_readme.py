"""The README's Python examples run as written, from the top of the repository."""

import re
from pathlib import Path

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
