"""The Python guide's code, executed block after block in one namespace from the repository
root, as a reader pastes it into a notebook."""

import os
import re

import pytest

from conftest import REPO, SHARED

GUIDE = REPO / "docs" / "guides" / "python.md"


def blocks():
    return re.findall(r"```python\n(.*?)```", GUIDE.read_text(), flags=re.S)


def test_the_guide_has_code():
    assert len(blocks()) >= 4


def test_the_guide_runs(monkeypatch):
    if not (SHARED / "maps" / "real").is_dir():
        pytest.skip(f"{SHARED / 'maps' / 'real'} is absent: the guide reads the nav2 depot map from it")
    pytest.importorskip("matplotlib")
    pytest.importorskip("pandas")
    monkeypatch.chdir(REPO)
    os.makedirs("target", exist_ok=True)
    out = REPO / "target" / "python-guide-depot.png"
    if out.exists():
        out.unlink()
    namespace = {}
    for code in blocks():
        exec(compile(code, str(GUIDE), "exec"), namespace)
    assert namespace["progress"].status == "arrived"
    assert out.stat().st_size > 10_000
    df = namespace["df"]
    assert len(df) == 6 and df["reached"].all()
    assert all(g["reached"] for g in namespace["goals"])


@pytest.mark.parametrize("page", ["README.md", "python/README.md"])
def test_the_readmes_python_runs(page):
    (code, *_) = re.findall(r"```python\n(.*?)```", (REPO / page).read_text(), flags=re.S)
    namespace = {}
    exec(compile(code, page, "exec"), namespace)
    assert namespace.get("rows") or namespace.get("p").status == "arrived"
