"""The README's "Python" section says what the code does: its quoted lines are examples/python_map.py's own
text (examples/python_map.py itself runs as the ctest example_python_map), and its command is the one the
example's docstring gives."""

import re
import textwrap

from conftest import SOURCE_DIR


def python_section():
    readme = (SOURCE_DIR / "README.md").read_text()
    match = re.search(r"^## Python\n(.*?)^## ", readme, re.S | re.M)
    assert match, "README needs a '## Python' section"
    return match.group(1)


def test_quoted_lines_are_the_example_file():
    section = python_section()
    quote = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    example = (SOURCE_DIR / "examples" / "python_map.py").read_text().splitlines()
    chunks = [c for c in re.split(r"^\.\.\.\n", quote, flags=re.M) if c.strip()]
    assert len(chunks) >= 5
    for chunk in chunks:
        wanted = textwrap.dedent(chunk).splitlines()
        found = any(
            textwrap.dedent("\n".join(example[i : i + len(wanted)])).splitlines() == wanted
            for i in range(len(example) - len(wanted) + 1)
        )
        assert found, f"README quotes lines that examples/python_map.py does not have:\n{chunk}"


def test_command_is_the_examples_own():
    section = python_section()
    command = re.search(r"```sh\n(.*?)\n```", section, re.S).group(1).strip()
    assert command in (SOURCE_DIR / "examples" / "python_map.py").read_text()
