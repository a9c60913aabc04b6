"""The Python examples of the README's "Python" section and of the user
guide's Python page (in order, as one script), and the package docstring's
example, run as written,
on the files `fairline demo` writes."""

from __future__ import annotations

import os
import re

import fairline
from conftest import REPO, need


def run_in(tmp_path, demo, code):
    (tmp_path / "fairline-demo").symlink_to(demo)
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        exec(compile(code, "example", "exec"), {})
    finally:
        os.chdir(cwd)


def test_readme_python_example_runs(tmp_path, demo):
    need("trimesh")
    text = (REPO / "README.md").read_text()
    section = text[text.index("\n## Python\n") :]
    section = section[: section.index("\n## ", 1)]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(blocks) == 1
    run_in(tmp_path, demo, blocks[0])
    assert (tmp_path / "wavy-smooth.ply").is_file()


def test_guide_python_example_runs(tmp_path, demo):
    need("trimesh")
    text = (REPO / "docs" / "guide" / "python.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) == 2
    # the page's examples follow one another: the second uses the first's V, F
    run_in(tmp_path, demo, "\n".join(blocks))
    assert (tmp_path / "wavy-smooth.ply").is_file()


def test_package_docstring_example_runs(tmp_path, demo):
    doc = fairline.__doc__
    code = doc[doc.index("Example::") + len("Example::") :]
    code = "\n".join(line[4:] for line in code.splitlines() if line.startswith("    "))
    assert "fairline.smooth" in code
    run_in(tmp_path, demo, code)
