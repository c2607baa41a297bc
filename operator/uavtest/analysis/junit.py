"""JUnit XML of runs, the report format CI systems read (pure: summaries in, bytes out).

One ``<testsuite>`` per run, one ``<testcase>`` per replica:

- ``pass`` → a passed case; ``fail`` → ``<failure message=reason>`` with the failed assertions;
  ``error`` (the bench's fault) → ``<error message=reason>``. CI systems count failures and
  errors apart, as uavtest does: an error is never a failure.
- Each case's ``<system-out>`` carries its seed, verdict, reason, attempts and the links to its
  artifacts (``flight.ulg``, ``result.json``: file paths locally, ``s3://`` URIs in a cluster).
  Artifact links go to ``system-out`` rather than case ``<properties>`` because the widely used
  Jenkins/Ant JUnit schema allows properties only on a suite.
- Suite ``<properties>``: ``uavtest.test``, ``uavtest.namespace``, ``uavtest.run-id``,
  ``uavtest.verdict``, ``uavtest.replicas``, ``uavtest.flakiness`` (``n/a`` when no replica was
  valid), ``uavtest.flaky``, ``uavtest.seeds`` (the replicas' seeds, e.g. ``7..9``); with
  obstacles, the UAV Testing Competition's score: ``uavtest.competition.points`` (total),
  ``uavtest.competition.points-mean``, ``uavtest.competition.hard-fails``,
  ``uavtest.competition.soft-fails``. A case's ``<system-out>`` also names its distances (3-D
  and the competition's 2-D) and points when it has them.

Case names are ``replica-<i>`` and the class name is the test's name, so a CI's history of a
case survives new seeds and run ids. Written with the standard library's ``xml.etree``: the
format is a few elements, and the operator image needs no extra dependency for it.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Mapping, Sequence

from uavtest.analysis.models import ReplicaResult, RunSummary, Verdict

__all__ = ["ArtifactLinks", "error_suite", "junit_document", "run_suite", "seeds_text"]

#: replica index → {artifact name (``flight.ulg``, ``result.json``): where it is}
ArtifactLinks = Mapping[int, Mapping[str, str]]


_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def _clean(text: str) -> str:
    """``text`` without the characters XML 1.0 cannot hold (a crash log may carry any byte)."""
    return _NOT_XML.sub("\ufffd", text)


def seeds_text(seeds: Sequence[int]) -> str:
    """``7..9`` for consecutive seeds, else the seeds comma-separated; ``-`` for none."""
    if not seeds:
        return "-"
    ordered = sorted(seeds)
    if len(ordered) == 1:
        return str(ordered[0])
    if ordered == list(range(ordered[0], ordered[-1] + 1)):
        return f"{ordered[0]}..{ordered[-1]}"
    return ",".join(str(s) for s in ordered)


def _seconds(value: float | None) -> str:
    return f"{max(value or 0.0, 0.0):.3f}"


def _failure_text(result: ReplicaResult) -> str:
    failed = [a.message or a.name for a in result.assertions if not a.passed]
    return "\n".join([result.reason, *(f"- {m}" for m in failed if m != result.reason)]).strip()


def _case(classname: str, result: ReplicaResult, links: Mapping[str, str]) -> ET.Element:
    case = ET.Element(
        "testcase",
        {"name": f"replica-{result.index}", "classname": classname, "time": _seconds(result.wall_time)},
    )
    reason = _clean(result.reason or result.verdict.value)
    if result.verdict is Verdict.FAIL:
        first = next((a.name for a in result.assertions if not a.passed), "assertion")
        ET.SubElement(case, "failure", {"message": reason, "type": first}).text = _clean(
            _failure_text(result)
        )
    elif result.verdict is Verdict.ERROR:
        ET.SubElement(case, "error", {"message": reason, "type": "bench-error"}).text = reason
    lines = [f"seed: {result.seed}", f"verdict: {result.verdict.value}"]
    if result.reason:
        lines.append(f"reason: {result.reason}")
    if result.attempts > 1:
        lines.append(f"attempts: {result.attempts}")
    m = result.metrics
    if m is not None and m.min_obstacle_distance is not None:
        lines.append(f"min obstacle distance: {m.min_obstacle_distance:.3f} m (3-D)")
    if m is not None and m.min_obstacle_distance_2d is not None:
        lines.append(f"competition distance: {m.min_obstacle_distance_2d:.3f} m (2-D)")
    if m is not None and m.competition_points is not None:
        lines.append(f"competition points: {m.competition_points}")
    lines += [f"{name}: {where}" for name, where in links.items()]
    ET.SubElement(case, "system-out").text = _clean("\n".join(lines))
    return case


def _properties(suite: ET.Element, values: Mapping[str, str]) -> None:
    props = ET.SubElement(suite, "properties")
    for name, value in values.items():
        ET.SubElement(props, "property", {"name": name, "value": _clean(value)})


def run_suite(summary: RunSummary, links: ArtifactLinks | None = None) -> ET.Element:
    """The ``<testsuite>`` of one run: its properties and a case per replica it lists."""
    links = links or {}
    results = sorted(summary.results, key=lambda r: r.index)
    suite = ET.Element(
        "testsuite",
        {
            "name": summary.test,
            "tests": str(len(results)),
            "failures": str(sum(r.verdict is Verdict.FAIL for r in results)),
            "errors": str(sum(r.verdict is Verdict.ERROR for r in results)),
            "skipped": "0",
            "time": _seconds(sum(r.wall_time or 0.0 for r in results)),
            "id": summary.run_id,
        },
    )
    flakiness = "n/a" if summary.flakiness is None else f"{summary.flakiness:.4g}"
    properties = {
        "uavtest.test": summary.test,
        "uavtest.namespace": summary.namespace,
        "uavtest.run-id": summary.run_id,
        "uavtest.verdict": summary.verdict.value,
        "uavtest.replicas": str(summary.replicas),
        "uavtest.flakiness": flakiness,
        "uavtest.flaky": "true" if summary.flaky else "false",
        "uavtest.seeds": seeds_text([r.seed for r in results]),
    }
    score = summary.competition_points
    if score is not None:
        properties["uavtest.competition.points"] = str(score.total)
        properties["uavtest.competition.points-mean"] = f"{score.mean:.4g}"
        properties["uavtest.competition.hard-fails"] = str(score.hard_fails)
        properties["uavtest.competition.soft-fails"] = str(score.soft_fails)
    if len(results) < summary.replicas:
        properties["uavtest.results-omitted"] = str(summary.replicas - len(results))
    _properties(suite, properties)
    for result in results:
        suite.append(_case(summary.test, result, links.get(result.index, {})))
    return suite


def error_suite(test: str, message: str, *, source: str = "") -> ET.Element:
    """A suite for a test that did not run to a result (e.g. the cluster was lost while it ran):
    one ``run`` case with an ``<error>``, so the CI report shows it instead of dropping it."""
    suite = ET.Element(
        "testsuite", {"name": test, "tests": "1", "failures": "0", "errors": "1", "skipped": "0", "time": "0"}
    )
    _properties(suite, {"uavtest.test": test, **({"uavtest.source": source} if source else {})})
    case = ET.SubElement(suite, "testcase", {"name": "run", "classname": test, "time": "0"})
    message = _clean(message)
    ET.SubElement(case, "error", {"message": message, "type": "bench-error"}).text = message
    return suite


def junit_document(suites: Iterable[ET.Element], name: str = "uavtest") -> bytes:
    """``<testsuites>`` around the suites, with the totals CI systems show; UTF-8 with a declaration."""
    root = ET.Element("testsuites", {"name": name})
    totals = {"tests": 0, "failures": 0, "errors": 0}
    time = 0.0
    for suite in suites:
        root.append(suite)
        for key in totals:
            totals[key] += int(suite.get(key, "0"))
        time += float(suite.get("time", "0"))
    for key, value in totals.items():
        root.set(key, str(value))
    root.set("time", _seconds(time))
    ET.indent(root)
    return ET.tostring(root, encoding="utf-8", xml_declaration=True) + b"\n"
