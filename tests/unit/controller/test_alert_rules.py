"""The chart's alert rules, checked and unit-tested by Prometheus' own promtool (Debian's package)
on synthetic series: each alert fires when its condition holds and stays quiet otherwise."""

from __future__ import annotations

import subprocess
from pathlib import Path
from typing import Any

import pytest
import yaml

from harness.prometheus import prometheus_binaries, render_rules

NS = 'test_namespace="team-a"'
RECONCILE_SUMMARY = "uavtest operator reconcile errors in run_changed: 1 within 10m"


def series(name: str, test: str, values: str) -> dict[str, str]:
    return {"series": f'{name}{{{NS},test="{test}"}}', "values": values}


def alert(test: str, summary: str, **annotations: str) -> dict[str, Any]:
    return {
        "exp_labels": {"severity": "warning", "test_namespace": "team-a", "test": test},
        "exp_annotations": {"summary": summary, **annotations},
    }


@pytest.fixture(scope="module")
def rules(tmp_path_factory: pytest.TempPathFactory) -> Path:
    try:
        return render_rules(tmp_path_factory.mktemp("rules"), failedRunsInARow=3, flakyRateAbove=0.2)
    except (subprocess.CalledProcessError, OSError) as e:
        pytest.skip(f"helm could not render the chart here (tests/cluster/build.sh helm): {e}")


@pytest.fixture(scope="module")
def promtool() -> Path:
    try:
        return prometheus_binaries()[1]
    except Exception as e:  # no Debian mirror reachable: say so
        pytest.skip(f"promtool (Debian's prometheus package) is not available: {e}")


def test_promtool_accepts_the_chart_rules(rules: Path, promtool: Path) -> None:
    out = subprocess.run([str(promtool), "check", "rules", str(rules)], capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr
    names = [r["alert"] for g in yaml.safe_load(rules.read_text())["groups"] for r in g["rules"]]
    assert names == [
        "UavTestTurnedFlaky",
        "UavTestFlakyRateHigh",
        "UavTestFailingRepeatedly",
        "UavTestOperatorReconcileErrors",
    ]


def test_each_alert_fires_on_its_condition_and_only_then(rules: Path, promtool: Path, tmp_path: Path) -> None:
    tests = {
        "rule_files": [str(rules)],
        "evaluation_interval": "1m",
        "tests": [
            {
                "interval": "1m",
                "input_series": [
                    # newest run flaky (0 < flakiness < 1); always-failing and always-passing are not flaky
                    series("uavtest_test_last_run_flakiness", "wobbly", "0 0 0.5 0.5"),
                    series("uavtest_test_last_run_flakiness", "broken", "1 1 1 1"),
                    series("uavtest_test_last_run_flakiness", "steady", "0 0 0 0"),
                    series("uavtest_test_flaky_rate", "wobbly", "0 0.1 0.25 0.25"),
                    series("uavtest_test_flaky_rate", "steady", "0 0 0 0"),
                    # 3 failed runs in a row fires (threshold 3), 2 does not
                    series("uavtest_test_failed_runs_in_a_row", "broken", "1 2 3 3"),
                    series("uavtest_test_failed_runs_in_a_row", "wobbly", "0 1 2 2"),
                    {"series": 'uavtest_reconcile_errors_total{handler="run_changed"}', "values": "0 0 1 1"},
                    {"series": 'uavtest_reconcile_errors_total{handler="test_changed"}', "values": "0 0 0 0"},
                ],
                "alert_rule_test": [
                    {"eval_time": "1m", "alertname": "UavTestTurnedFlaky", "exp_alerts": []},
                    {
                        "eval_time": "3m",
                        "alertname": "UavTestTurnedFlaky",
                        "exp_alerts": [
                            alert(
                                "wobbly",
                                "UavTest team-a/wobbly turned flaky",
                                description="Its newest run had flakiness 0.50 (failed / valid replicas).",
                            )
                        ],
                    },
                    {"eval_time": "1m", "alertname": "UavTestFlakyRateHigh", "exp_alerts": []},
                    {
                        "eval_time": "3m",
                        "alertname": "UavTestFlakyRateHigh",
                        "exp_alerts": [
                            alert("wobbly", "UavTest team-a/wobbly is flaky in 25% of its kept runs")
                        ],
                    },
                    {"eval_time": "1m", "alertname": "UavTestFailingRepeatedly", "exp_alerts": []},
                    {
                        "eval_time": "3m",
                        "alertname": "UavTestFailingRepeatedly",
                        "exp_alerts": [alert("broken", "UavTest team-a/broken failed 3 runs in a row")],
                    },
                    {"eval_time": "1m", "alertname": "UavTestOperatorReconcileErrors", "exp_alerts": []},
                    {
                        "eval_time": "3m",
                        "alertname": "UavTestOperatorReconcileErrors",
                        "exp_alerts": [
                            {
                                "exp_labels": {"severity": "warning", "handler": "run_changed"},
                                "exp_annotations": {"summary": RECONCILE_SUMMARY},
                            }
                        ],
                    },
                ],
            }
        ],
    }
    path = tmp_path / "alerts_test.yaml"
    path.write_text(yaml.safe_dump(tests, sort_keys=False))
    out = subprocess.run([str(promtool), "test", "rules", str(path)], capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr
