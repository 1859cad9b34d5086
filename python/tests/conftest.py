"""Shared paths of the demcon Python tests."""

from pathlib import Path

import pytest

DATA = Path(__file__).parent / "data"


@pytest.fixture
def homogeneous() -> Path:
    return DATA / "homogeneous.ron"


@pytest.fixture
def long_transient() -> Path:
    return DATA / "long-transient.ron"
