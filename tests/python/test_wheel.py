"""The built wheels use the stable ABI (abi3, Python >= 3.9)."""

import os
from pathlib import Path


def test_every_wheel_is_abi3():
    wheels = sorted(Path(os.environ["LAGC_WHEELS"]).glob("*/*.whl"))
    assert len(wheels) >= 2, wheels
    for wheel in wheels:
        # name-version-python-abi-platform.whl
        python, abi = wheel.stem.split("-")[2:4]
        assert (python, abi) == ("cp39", "abi3"), wheel.name
