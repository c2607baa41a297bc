"""The CRD: generated from the models, structural, committed copies identical, agreeing with the models."""

from __future__ import annotations

import re
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pytest
import yaml
from pydantic import ValidationError

from uavtest.spec.crd import IMMUTABLE_MESSAGE, crd, crd_yaml, run_crd
from uavtest.spec.loaders import load_test
from uavtest.spec.models import UavTestSpec
from uavtest.spec.render import render
from uavtest.spec.status import (
    MAX_REASON_LENGTH,
    MAX_STATUS_RESULTS,
    Condition,
    ConditionStatus,
    ReplicaStatus,
    ReplicaVerdict,
    TestStatus,
    UavTestStatus,
    compact_results,
)

TYPES = {"object", "array", "string", "integer", "number", "boolean"}
FORBIDDEN = {"$ref", "$defs", "anyOf", "allOf", "oneOf", "not", "const", "title", "default", "definitions"}


def _version() -> dict[str, Any]:
    [version] = crd()["spec"]["versions"]
    return version


def _schema() -> dict[str, Any]:
    return _version()["schema"]["openAPIV3Schema"]


@pytest.mark.parametrize("relative", ["crds/uavtest.yaml", "charts/uavtest/crds/uavtest.yaml"])
def test_committed_crd_matches_the_generator(repo_root: Path, relative: str) -> None:
    committed = (repo_root / relative).read_text()
    assert committed == crd_yaml(), f"{relative} is stale: run `uavtest crd > {relative}`"


def test_crd_command_prints_the_generated_crd(uavtest) -> None:
    result = uavtest("crd")
    assert result.returncode == 0
    assert result.stdout == crd_yaml()
    assert list(yaml.safe_load_all(result.stdout)) == [crd(), run_crd()]


def _walk(node: dict[str, Any], path: str, seen: list[str]) -> None:
    seen.append(path)
    assert not FORBIDDEN & set(node), f"{path}: {FORBIDDEN & set(node)}"
    if node.get("x-kubernetes-preserve-unknown-fields") or node.get("x-kubernetes-int-or-string"):
        assert "properties" not in node or node.get("type") == "object", path
    else:
        assert node.get("type") in TYPES, f"{path}: no type"
    for key in ("exclusiveMinimum", "exclusiveMaximum"):
        if key in node:
            assert node[key] is True, f"{path}: {key} must be a boolean (OpenAPI v3.0)"
            assert ("minimum" if key == "exclusiveMinimum" else "maximum") in node, path
    if node.get("type") == "object":
        assert not ("properties" in node and "additionalProperties" in node), path
        for name in node.get("required", []):
            assert name in node.get("properties", {}), f"{path}: required {name} is not a property"
        for name, child in node.get("properties", {}).items():
            _walk(child, f"{path}.{name}", seen)
        extra = node.get("additionalProperties")
        if isinstance(extra, dict):
            _walk(extra, f"{path}.*", seen)
        else:
            assert extra is None, f"{path}: additionalProperties must be a schema"
    if node.get("type") == "array":
        assert isinstance(node.get("items"), dict), f"{path}: arrays need one items schema"
        _walk(node["items"], f"{path}[]", seen)
    if "enum" in node:
        assert node.get("type") == "string" and all(isinstance(v, str) for v in node["enum"]), path


def test_schema_is_structural() -> None:
    seen: list[str] = []
    _walk(_schema(), "", seen)
    assert ".spec.world.obstacles[].size.l" in seen
    assert ".status.conditions[].lastTransitionTime" in seen
    plan = _schema()["properties"]["spec"]["properties"]["mission"]["properties"]["plan"]
    assert plan["x-kubernetes-preserve-unknown-fields"] is True and plan["type"] == "object"
    params = _schema()["properties"]["spec"]["properties"]["vehicle"]["properties"]["params"]
    assert params["additionalProperties"] == {"type": "number"}


def test_schema_has_every_model_field() -> None:
    def fields(model: Any) -> set[str]:
        return {f.alias or n for n, f in model.model_fields.items()}

    spec = _schema()["properties"]["spec"]["properties"]
    assert set(spec) == fields(UavTestSpec)
    assert set(_schema()["properties"]["status"]["properties"]) == fields(TestStatus)
    run_schema = run_crd()["spec"]["versions"][0]["schema"]["openAPIV3Schema"]
    assert set(run_schema["properties"]["status"]["properties"]) == fields(UavTestStatus)


def test_crd_names_subresources_and_columns() -> None:
    spec = crd()["spec"]
    assert crd()["metadata"]["name"] == "uavtests.uavtest.io"
    assert spec["group"] == "uavtest.io" and spec["scope"] == "Namespaced"
    assert spec["names"]["shortNames"] == ["uavt"] and spec["names"]["kind"] == "UavTest"
    assert spec["names"]["categories"]
    version = _version()
    assert version["subresources"] == {"status": {}}
    assert version["served"] and version["storage"]
    columns = {c["name"]: c for c in version["additionalPrinterColumns"]}
    for name in ("Phase", "Last-Run", "Flakiness", "Runs", "Flaky-Rate", "Age"):
        assert name in columns and columns[name].get("priority", 0) == 0
    assert columns["Phase"]["jsonPath"] == ".status.phase"
    assert columns["Age"]["type"] == "date"
    run = run_crd()["spec"]
    assert run["names"]["kind"] == "UavTestRun" and run["names"]["shortNames"] == ["uavtr"]
    run_columns = {c["name"]: c for c in run["versions"][0]["additionalPrinterColumns"]}
    for name in ("Test", "Phase", "Replicas", "Passed", "Failed", "Flakiness", "Age"):
        assert name in run_columns and run_columns[name].get("priority", 0) == 0
    assert run_columns["Succeeded"]["jsonPath"] == '.status.conditions[?(@.type=="Succeeded")].status'
    # columns point at fields the status schemas have
    for doc, cols in ((crd(), columns), (run_crd(), run_columns)):
        props = doc["spec"]["versions"][0]["schema"]["openAPIV3Schema"]["properties"]["status"]["properties"]
        for column in cols.values():
            path = column["jsonPath"]
            if path.startswith(".status.") and "[" not in path:
                head, _, tail = path.removeprefix(".status.").partition(".")
                assert head in props and (not tail or tail in props[head]["properties"])


def test_a_tests_spec_may_change_and_a_runs_spec_is_frozen() -> None:
    rules = _schema()["properties"]["spec"]["x-kubernetes-validations"]
    assert not any("oldSelf" in r["rule"] for r in rules)  # GitOps edits a test in place
    run_rules = run_crd()["spec"]["versions"][0]["schema"]["openAPIV3Schema"]["properties"]["spec"][
        "x-kubernetes-validations"
    ]
    assert [r["message"] for r in run_rules] == [IMMUTABLE_MESSAGE]
    assert run_rules[0]["rule"].startswith("self == oldSelf")


def test_cross_field_rules_mirror_the_model_validators() -> None:
    spec = _schema()["properties"]["spec"]
    rules = {r["message"]: r["rule"] for r in spec["x-kubernetes-validations"]}
    assert "has(self.mission)" in rules["a test needs a mission or commands (or both)"]
    mission = spec["properties"]["mission"]
    assert [r["message"] for r in mission["x-kubernetes-validations"]] == [
        "give exactly one of plan, planFile, waypoints"
    ]


def test_committed_yaml_quotes_what_yaml_1_1_reads_as_booleans(repo_root: Path) -> None:
    # kubectl (Go, YAML 1.1) reads a bare y as true: the obstacle field y must stay a string
    text = (repo_root / "crds" / "uavtest.yaml").read_text()
    assert re.search(r"^\s*y:", text, re.MULTILINE) is None and "[x, y" not in text
    assert "'y':" in text and "[x, 'y']" in text


# ------------------------------------------------------------------ the schema agrees with the models


@pytest.fixture(scope="module")
def validator() -> Any:
    oas = pytest.importorskip("openapi_schema_validator")
    return oas.OAS30Validator(_schema())


@pytest.mark.parametrize(
    "relative",
    [
        "competition/snippets/case_studies/mission2.yaml",
        "aerialist/samples/tests/mission1-k8s.yaml",
    ],
)
def test_rendered_manifests_satisfy_the_schema(shared_data: Path, validator: Any, relative: str) -> None:
    validator.validate(render(load_test(shared_data / relative)))


@pytest.mark.parametrize(
    ("path", "value"),
    [
        (("world", "obstacles", 0, "size", "l"), -5),
        (("commands", 0, "mode"), "acrobatic"),
        (("replicas",), 0),
        (("commands", 0, "sticks"), {"x": 1.5}),
    ],
)
def test_the_schema_refuses_what_the_model_refuses(validator: Any, path: tuple[Any, ...], value: Any) -> None:
    spec: dict[str, Any] = {
        "replicas": 2,
        "world": {"obstacles": [{"size": {"l": 1, "w": 1, "h": 1}, "position": {"x": 0, "y": 0}}]},
        "commands": [{"at": 1, "action": "mode", "mode": "hold"}],
    }
    UavTestSpec.model_validate(spec)
    validator.validate({"apiVersion": "uavtest.io/v1alpha1", "kind": "UavTest", "metadata": {}, "spec": spec})
    node: Any = spec
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    with pytest.raises(ValidationError):
        UavTestSpec.model_validate(spec)
    errors = list(validator.iter_errors({"kind": "UavTest", "spec": spec}))
    assert errors


# ------------------------------------------------------------------ status


def test_status_dump_satisfies_the_schema(validator: Any) -> None:
    now = datetime(2025, 1, 2, 3, 4, 5, tzinfo=UTC)
    status = UavTestStatus(
        phase="Failed",
        replicas=3,
        passed=2,
        failed=1,
        flakiness=1 / 3,
        flaky=True,
        run_id="r1",
        start_time=now,
        completion_time=now,
        observed_generation=1,
        conditions=[
            Condition(
                type="Succeeded",
                status=ConditionStatus.FALSE,
                reason="ReplicasFailed",
                last_transition_time=now,
            )
        ],
        results=[
            ReplicaStatus(
                index=1,
                seed=8,
                verdict="fail",
                min_distance=0.8,
                min_distance_2d=0.7,
                points=2,
                reason="soft fail: min distance 0.80 m < 1.50 m",
            )
        ],
    )
    doc = status.dump()
    assert doc["conditions"][0]["lastTransitionTime"] == "2025-01-02T03:04:05Z"
    validator.validate({"kind": "UavTest", "spec": {"commands": [{"at": 0, "action": "arm"}]}, "status": doc})
    assert UavTestStatus.model_validate(doc) == status


def test_condition_shape() -> None:
    with pytest.raises(ValidationError):
        Condition(
            type="succeeded",
            status="True",
            reason="AllReplicasPassed",
            last_transition_time=datetime.now(UTC),
        )
    with pytest.raises(ValidationError):
        Condition(
            type="Succeeded", status="yes", reason="AllReplicasPassed", last_transition_time=datetime.now(UTC)
        )


def test_results_are_bounded_failures_first() -> None:
    verdicts = ["pass", "fail", "error"]
    replicas = [ReplicaStatus(index=i, seed=100 + i, verdict=verdicts[i % 3]) for i in range(120)]
    kept, omitted = compact_results(replicas)
    assert len(kept) == MAX_STATUS_RESULTS and omitted == 120 - MAX_STATUS_RESULTS
    assert [r.verdict for r in kept[:40]] == [ReplicaVerdict.FAIL] * 40
    assert [r.index for r in kept[:3]] == [1, 4, 7]
    assert kept[40].verdict == ReplicaVerdict.ERROR
    with pytest.raises(ValidationError):
        UavTestStatus(results=replicas)
    assert len(ReplicaStatus(index=0, seed=0, verdict="error", reason="x" * 1000).reason) == MAX_REASON_LENGTH


def test_no_category_shadows_a_resource_name() -> None:
    """kubectl expands a category before it reads a word as a resource: a category named like a
    resource would make `kubectl get uavtest NAME` ask for every kind in it."""
    words = set()
    for doc in (crd(), run_crd()):
        n = doc["spec"]["names"]
        words |= {n["plural"], n["singular"], *n["shortNames"]}
    for doc in (crd(), run_crd()):
        assert not set(doc["spec"]["names"]["categories"]) & words
