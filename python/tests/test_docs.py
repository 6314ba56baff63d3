"""docs/python.md is what python/tools/python_docs.py generates from the
docstrings, and every public name of the module is documented there."""
import subprocess
import sys

import lodestone
from conftest import SOURCE_DIR


def test_committed_docs_equal_the_generated_ones():
    result = subprocess.run([sys.executable, str(SOURCE_DIR / "python/tools/python_docs.py"), "--check"],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr


def test_every_public_name_has_a_docstring_and_a_section():
    text = (SOURCE_DIR / "docs/python.md").read_text()
    for name, value in lodestone.__dict__.items():
        if name.startswith("_") or not callable(value):
            continue
        assert value.__doc__, name
        assert f"`{name}" in text or f"class `{name}`" in text, name
