"""Fixtures of the controller unit tests."""

from __future__ import annotations

from typing import Any

import pytest

from .controller_bodies import uavtest_body


@pytest.fixture
def test_body() -> dict[str, Any]:
    return uavtest_body()
