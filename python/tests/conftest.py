"""Shared helpers of the Python tests: the built tool (TESSERA_TOOL, set by ctest) and the
source tree (TESSERA_SOURCE_DIR)."""
import json
import os
import pathlib
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("TESSERA_SOURCE_DIR", pathlib.Path(__file__).parents[2]))


@pytest.fixture
def tool():
    """Runs the built `tessera` tool with --json and returns its parsed output."""
    path = os.environ.get("TESSERA_TOOL", "")
    if not path:
        pytest.skip("TESSERA_TOOL is not set (the tool is not built)")

    def run(*arguments):
        done = subprocess.run([path, *arguments, "--json"], capture_output=True, text=True,
                              check=True)
        return json.loads(done.stdout)

    return run
