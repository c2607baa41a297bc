"""The store layout: the keys every part of uavtest agrees on."""

from __future__ import annotations

import pytest

from uavtest.errors import BadInput
from uavtest.store.layout import aggregate_key, replica_key, replica_prefix, run_prefix


def test_replica_key_follows_the_design_layout() -> None:
    key = replica_key("local", "hover", "run-1", 3, "result.json")
    assert key == "local/hover/run-1/replica-3/result.json"


def test_aggregate_key_follows_the_design_layout() -> None:
    assert aggregate_key("ci", "mission2", "20240101-abc", "summary.json") == (
        "ci/mission2/20240101-abc/aggregate/summary.json"
    )


def test_replica_keys_share_the_run_prefix() -> None:
    prefix = run_prefix("local", "t", "r")
    assert replica_key("local", "t", "r", 0, "flight.ulg").startswith(prefix)
    assert aggregate_key("local", "t", "r", "average.csv").startswith(prefix)
    assert replica_prefix("local", "t", "r", 7) == "local/t/r/replica-7/"


@pytest.mark.parametrize(
    ("field", "args"),
    [
        ("namespace", ("", "t", "r", 0, "x")),
        ("test", ("local", "a/b", "r", 0, "x")),
        ("run_id", ("local", "t", "..", 0, "x")),
        ("name", ("local", "t", "r", 0, "../escape")),
        ("index", ("local", "t", "r", -1, "x")),
    ],
)
def test_a_segment_that_would_break_the_layout_is_refused_naming_the_field(
    field: str, args: tuple[str, str, str, int, str]
) -> None:
    with pytest.raises(BadInput) as e:
        replica_key(*args)
    assert e.value.field == field
