"""The Python examples run as written: the README's "Python" example (extracted from the README
itself, so an edit there that breaks it fails here) and examples/python/compare_strategies.py on
its small scenes."""
import re
import subprocess
import sys

import tessera
from conftest import SOURCE_DIR


def run_python(*arguments):
    return subprocess.run([sys.executable, *arguments], capture_output=True, text=True,
                          check=True, cwd=SOURCE_DIR).stdout


def test_readme_example_runs_as_written():
    readme = (SOURCE_DIR / "README.md").read_text()
    section = readme.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    code, _ = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(code.strip().splitlines()) == 10
    lines = run_python("-c", code).splitlines()
    assert [line.split()[0] for line in lines[:-1]] == list(tessera.strategies())
    residual, *extent = lines[-1].replace("[", " ").replace("]", " ").split()
    assert float(residual) > 0 and all(float(e) > 0 for e in extent)


def test_readme_collision_example_runs_as_written():
    readme = (SOURCE_DIR / "README.md").read_text()
    section = readme.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    _, code = re.findall(r"```python\n(.*?)```", section, re.S)
    contacts_mean, most_at_a_particle, penetration = run_python(
        "-c", "import tessera\n" + code).split()
    assert float(contacts_mean) > 100 and int(most_at_a_particle) > 0
    assert float(penetration) <= 0.005


def test_compare_strategies_covers_every_scene_and_strategy():
    out = run_python(str(SOURCE_DIR / "examples" / "python" / "compare_strategies.py"),
                     "--quick", "--no-plot")
    rows = [line for line in out.splitlines()[1:] if line.strip()]
    strategies = list(tessera.strategies())
    assert len(rows) == 3 * len(strategies)
    for row in rows:
        assert any(f" {name} " in row for name in strategies), row
        colours, bound = (int(v) for v in row.split()[-6:-4])
        assert colours >= bound > 0, row
