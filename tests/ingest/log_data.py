"""Where the committed Killian excerpt is (tests/data/killian/README.md says where it comes from)."""

from pathlib import Path

EXCERPT = Path(__file__).resolve().parents[1] / "data" / "killian" / "killian_0-359.g2o"
