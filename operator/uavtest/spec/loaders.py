"""Load a test file: native UavTest YAML or Aerialist / competition YAML, detected by its keys.

What comes back is a validated ``UavTest`` that is complete in itself: ``planFile``,
``paramsFile`` and ``commandsFile`` are read and inlined (``mission.plan``, ``vehicle.params``,
``commands``), and ``assertions.similarity.logFile`` is made an absolute path, so the
simulator, the runner and the analysis never look at the test file's folder again.
Every problem is a ``BadInput`` (file, field path, value, what is allowed) or a
``MissingFile`` (the path as written and the test file naming it).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from uavtest.errors import BadInput, MissingFile
from uavtest.spec.aerialist import dns_name, from_aerialist, is_aerialist
from uavtest.spec.commands_csv import read_commands_csv
from uavtest.spec.models import API_VERSION, KIND, UavTest
from uavtest.spec.params_csv import read_params_csv
from uavtest.spec.paths import resolve_reference
from uavtest.spec.plan import parse_plan, plan_home, read_plan
from uavtest.spec.px4_params import check_params
from uavtest.spec.validation import bad_input_from, model_fields_of
from uavtest.spec.yaml_io import check_file_size, parse_yaml

__all__ = ["load_test", "load_test_text", "resolve_references"]


def load_test(path: Path) -> UavTest:
    """The test in ``path`` (native or Aerialist YAML), with its referenced files inlined."""
    path = Path(path)
    check_file_size(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise MissingFile(str(path)) from None
    except IsADirectoryError:
        raise BadInput("is a folder, not a test file", file=str(path), allowed="a YAML test file") from None
    except UnicodeDecodeError:
        raise BadInput("not a text file", file=str(path), allowed="a YAML test file (UTF-8)") from None
    except OSError as e:
        raise BadInput(f"cannot read: {e.strerror}", file=str(path)) from None
    return load_test_text(text, str(path), base_file=path)


def load_test_text(text: str, source_name: str, *, base_file: Path | None = None) -> UavTest:
    """The test in YAML ``text``; ``source_name`` names it in messages.

    Referenced files are searched from ``base_file``'s folder upwards (the current folder
    when there is no file, e.g. a manifest read from a cluster).
    """
    doc = parse_yaml(text, source_name)
    if doc is None:
        raise BadInput(
            "the file is empty",
            file=source_name,
            allowed=f"a UavTest (apiVersion: {API_VERSION}, kind: {KIND}) or an Aerialist test",
        )
    if not isinstance(doc, Mapping):
        raise BadInput(
            "a test file must be a mapping",
            file=source_name,
            value=type(doc).__name__,
            allowed=f"a UavTest (apiVersion: {API_VERSION}, kind: {KIND}) or an Aerialist test",
        )
    if is_aerialist(doc):
        doc = from_aerialist(doc, source_name, base_file)
    test = _validate_native(doc, source_name, base_file)
    return resolve_references(test, base_file, source=source_name)


def _validate_native(doc: Mapping[str, Any], source: str, base_file: Path | None) -> UavTest:
    allowed_kind = f"apiVersion: {API_VERSION} and kind: {KIND} (or an Aerialist test with robot/drone, ...)"
    if "apiVersion" not in doc:
        raise BadInput(
            "not a UavTest: apiVersion is missing", file=source, field="apiVersion", allowed=allowed_kind
        )
    if doc["apiVersion"] != API_VERSION:
        raise BadInput(
            "unsupported apiVersion",
            file=source,
            field="apiVersion",
            value=doc["apiVersion"],
            allowed=API_VERSION,
        )
    if doc.get("kind") != KIND:
        raise BadInput("not a UavTest", file=source, field="kind", value=doc.get("kind"), allowed=KIND)
    data = dict(doc)
    metadata = data.get("metadata")
    if (
        metadata is None or (isinstance(metadata, Mapping) and "name" not in metadata)
    ) and base_file is not None:
        data["metadata"] = {**(metadata or {}), "name": dns_name(base_file.stem)}
    for top in data:
        if top not in ("apiVersion", "kind", "metadata", "spec", "status"):
            raise BadInput(
                f"unknown field '{top}'",
                file=source,
                field=str(top),
                allowed=", ".join([*model_fields_of(UavTest), "status"]),
            )
    data.pop("status", None)  # written by the operator; a manifest fetched from a cluster may carry it
    try:
        return UavTest.model_validate(data)
    except ValidationError as e:
        raise bad_input_from(e, source=source, root=UavTest) from None


def resolve_references(test: UavTest, test_file: Path | None, *, source: str | None = None) -> UavTest:
    """``test`` with planFile / paramsFile / commandsFile inlined and logFile made absolute.

    An inline plan is checked too. A plan's ``plannedHomePosition`` becomes ``world.home``
    unless the test gives a home itself.
    """
    source = source or (str(test_file) if test_file is not None else test.metadata.name)
    spec = test.spec
    doc = test.model_dump(by_alias=True, exclude_none=True, mode="json")
    s = doc["spec"]
    mission = spec.mission
    plan: dict[str, Any] | None = None
    plan_source = source
    if mission is not None and mission.plan_file is not None:
        path = resolve_reference(mission.plan_file, test_file, field="spec.mission.planFile")
        plan, plan_source = read_plan(path), str(path)
        s["mission"]["plan"] = plan
        del s["mission"]["planFile"]
    elif mission is not None and mission.plan is not None:
        plan = mission.plan
    if plan is not None:
        prefix = "" if plan_source != source else "spec.mission.plan"
        home = plan_home(plan, plan_source, prefix=prefix)
        parse_plan(plan, plan_source, home_alt=(home or spec.world.home).alt, prefix=prefix)
        if home is not None and "home" not in spec.world.model_fields_set:
            s["world"]["home"] = home.dump()
    check_params(spec.vehicle.params, source=source, field_prefix="spec.vehicle.params")
    if spec.vehicle.params_file is not None:
        path = resolve_reference(spec.vehicle.params_file, test_file, field="spec.vehicle.paramsFile")
        from_file = read_params_csv(path)
        check_params({k: v for k, v in from_file.items() if k not in spec.vehicle.params}, source=str(path))
        s["vehicle"]["params"] = {**from_file, **spec.vehicle.params}
        del s["vehicle"]["paramsFile"]
    if spec.commands_file is not None:
        path = resolve_reference(spec.commands_file, test_file, field="spec.commandsFile")
        merged = [*spec.commands, *read_commands_csv(path)]
        s["commands"] = [c.dump() for c in sorted(merged, key=lambda c: c.at)]
        del s["commandsFile"]
    similarity = spec.assertions.similarity
    if similarity is not None and similarity.log_file is not None:
        path = resolve_reference(similarity.log_file, test_file, field="spec.assertions.similarity.logFile")
        s["assertions"]["similarity"]["logFile"] = str(path)
    try:
        return UavTest.model_validate(doc)
    except ValidationError as e:  # only when a referenced file brought something the model refuses
        raise bad_input_from(e, source=source, root=UavTest) from None
