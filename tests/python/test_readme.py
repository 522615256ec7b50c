"""The README's Python lines run as written."""

from conftest import ROOT


def test_the_readmes_python_block_runs():
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## From Python"):]
    block = section[section.index("```python") + len("```python"):]
    block = block[:block.index("```")]
    scope = {}
    exec(compile(block, "README.md", "exec"), scope)
    sol = scope["sol"]
    assert sol.y.shape == (51, 4) and len(scope["sols"]) == 1000
    assert scope["it"].t == 2.5
