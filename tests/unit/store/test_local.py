"""LocalStore: artifacts as files in a directory."""

from __future__ import annotations

from pathlib import Path

import pytest

from uavtest.errors import BadInput
from uavtest.store import ArtifactNotFound, ArtifactStore, LocalStore


def test_put_then_get_returns_the_same_bytes(tmp_path: Path) -> None:
    store = LocalStore(tmp_path)
    store.put("local/t/r/replica-0/flight.ulg", b"ULog\x01\x12\x35")
    assert store.get("local/t/r/replica-0/flight.ulg") == b"ULog\x01\x12\x35"
    assert (tmp_path / "local/t/r/replica-0/flight.ulg").read_bytes() == b"ULog\x01\x12\x35"


def test_put_replaces_and_leaves_no_temporary_files(tmp_path: Path) -> None:
    store = LocalStore(tmp_path)
    store.put("a/result.json", b"1")
    store.put("a/result.json", b"22")
    assert store.get("a/result.json") == b"22"
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == ["result.json"]


def test_exists_and_list_by_prefix(tmp_path: Path) -> None:
    store = LocalStore(tmp_path)
    for key in ("ns/t/r/replica-1/result.json", "ns/t/r/replica-0/result.json", "ns/t/other/x.csv"):
        store.put(key, b"x")
    assert store.exists("ns/t/r/replica-1/result.json")
    assert not store.exists("ns/t/r/replica-2/result.json")
    assert store.list("ns/t/r/") == ["ns/t/r/replica-0/result.json", "ns/t/r/replica-1/result.json"]
    assert len(store.list()) == 3


def test_list_of_a_store_that_was_never_written_is_empty(tmp_path: Path) -> None:
    assert LocalStore(tmp_path / "nothing-yet").list() == []


def test_get_of_a_missing_key_names_the_key(tmp_path: Path) -> None:
    with pytest.raises(ArtifactNotFound) as e:
        LocalStore(tmp_path).get("ns/t/r/replica-4/result.json")
    assert "ns/t/r/replica-4/result.json" in str(e.value)


@pytest.mark.parametrize("key", ["../outside", "/abs/key", "a//b", "a/./b", ""])
def test_keys_that_would_leave_the_root_are_refused(tmp_path: Path, key: str) -> None:
    with pytest.raises(BadInput):
        LocalStore(tmp_path / "root").put(key, b"x")
    assert not (tmp_path / "outside").exists()


def test_url_is_a_file_uri_of_the_artifact(tmp_path: Path) -> None:
    url = LocalStore(tmp_path).url("a/b.json")
    assert url == (tmp_path / "a" / "b.json").resolve().as_uri()


def test_local_store_satisfies_the_protocol(tmp_path: Path) -> None:
    assert isinstance(LocalStore(tmp_path), ArtifactStore)
