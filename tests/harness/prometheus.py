"""Prometheus and promtool from Debian's package (tests/cluster/build.sh prometheus), and the
chart's alert rules rendered by Helm, for the tests that evaluate the dashboard and the alerts.

    rules = render_rules(tmp_path, failedRunsInARow=2)   # the PrometheusRule's groups, as a file
    with PrometheusServer(tmp_path, scrape_configs, rules) as prom:
        prom.query('uavtest_test_flaky_rate')             # -> list of {"metric": ..., "value": ...}
"""

from __future__ import annotations

import json
import shutil
import subprocess
import time
import urllib.error
import urllib.parse
import urllib.request
from pathlib import Path
from types import TracebackType
from typing import Any

import yaml

from harness.cluster import BIN_DIR, REPO_ROOT, build_binaries, free_ports

__all__ = ["PrometheusServer", "helm_binary", "prometheus_binaries", "render_rules"]

CHART = REPO_ROOT / "charts" / "uavtest"


def prometheus_binaries() -> tuple[Path, Path]:
    """(prometheus, promtool), unpacked from Debian's package into the cache on first use."""
    prom, tool = BIN_DIR / "prometheus", BIN_DIR / "promtool"
    if not (prom.exists() and tool.exists()):
        build_binaries("prometheus")
    return prom, tool


def helm_binary() -> Path:
    found = shutil.which("helm")
    if found:
        return Path(found)
    helm = BIN_DIR / "helm"
    if not helm.exists():
        build_binaries("helm")
    return helm


def render_rules(out_dir: Path, **values: object) -> Path:
    """The chart's PrometheusRule (``metrics.prometheusRule.<key>=value`` set from ``values``)
    rendered by ``helm template``; its ``spec`` (the rule groups) written as a Prometheus rule file."""
    args = [str(helm_binary()), "template", "rel", str(CHART), "--set", "metrics.prometheusRule.enabled=true"]
    for key, value in values.items():
        args += ["--set", f"metrics.prometheusRule.{key}={value}"]
    args += ["--show-only", "templates/prometheusrule.yaml"]
    rendered = yaml.safe_load(subprocess.run(args, check=True, capture_output=True, text=True).stdout)
    path = out_dir / "uavtest-rules.yaml"
    path.write_text(yaml.safe_dump(rendered["spec"], sort_keys=False))
    return path


class PrometheusServer:
    """A real Prometheus on 127.0.0.1 with the given scrape configs and rule file."""

    def __init__(
        self,
        workdir: Path,
        scrape_configs: list[dict[str, Any]],
        rules: Path | None = None,
        *,
        interval: str = "2s",
    ) -> None:
        self.workdir = workdir
        self.port = free_ports(1)[0]
        self.url = f"http://127.0.0.1:{self.port}"
        config = {
            "global": {
                "scrape_interval": interval,
                "scrape_timeout": interval,
                "evaluation_interval": interval,
            },
            "scrape_configs": scrape_configs,
        }
        if rules is not None:
            config["rule_files"] = [str(rules)]
        self.config = workdir / "prometheus.yml"
        self.config.write_text(yaml.safe_dump(config, sort_keys=False))
        self.log = workdir / "prometheus.log"
        self._proc: subprocess.Popen[bytes] | None = None
        self.started = 0.0  # time.time() when it answered ready

    def __enter__(self) -> PrometheusServer:
        prom, tool = prometheus_binaries()
        check = subprocess.run(
            [str(tool), "check", "config", str(self.config)], capture_output=True, text=True
        )
        if check.returncode != 0:
            raise RuntimeError(f"promtool check config: {check.stdout}{check.stderr}")
        self._proc = subprocess.Popen(
            [
                str(prom),
                f"--config.file={self.config}",
                f"--storage.tsdb.path={self.workdir / 'tsdb'}",
                f"--web.listen-address=127.0.0.1:{self.port}",
            ],
            stdout=self.log.open("wb"),
            stderr=subprocess.STDOUT,
        )
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if self._proc.poll() is not None:
                raise RuntimeError(
                    f"prometheus exited {self._proc.returncode}: {self.log.read_text()[-2000:]}"
                )
            try:
                with urllib.request.urlopen(f"{self.url}/-/ready", timeout=2) as resp:
                    if resp.status == 200:
                        self.started = time.time()
                        return self
            except OSError:
                time.sleep(0.3)
        raise RuntimeError(f"prometheus not ready within 60 s: {self.log.read_text()[-2000:]}")

    def __exit__(self, *exc: type[BaseException] | BaseException | TracebackType | None) -> None:
        if self._proc is not None and self._proc.poll() is None:
            self._proc.terminate()
            try:
                self._proc.wait(15)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait(5)

    def api(self, path: str, **params: str) -> Any:
        query = urllib.parse.urlencode(params)
        try:
            with urllib.request.urlopen(f"{self.url}/api/v1/{path}?{query}", timeout=30) as resp:
                body = json.load(resp)
        except urllib.error.HTTPError as e:  # Prometheus explains a bad query in the body
            raise RuntimeError(f"{path} {params}: HTTP {e.code}: {e.read().decode(errors='replace')}") from e
        if body.get("status") != "success":
            raise RuntimeError(f"{path} {params}: {body}")
        return body["data"]

    def query(self, expr: str) -> list[dict[str, Any]]:
        """An instant query's result vector (a scalar comes back as one unlabelled sample)."""
        data = self.api("query", query=expr)
        if data["resultType"] == "scalar":
            return [{"metric": {}, "value": data["result"]}]
        return list(data["result"])

    def query_range(self, expr: str, seconds: float, step: str = "2s") -> list[dict[str, Any]]:
        end = time.time()
        data = self.api("query_range", query=expr, start=str(end - seconds), end=str(end), step=step)
        return list(data["result"])

    def targets(self) -> list[dict[str, Any]]:
        return list(self.api("targets")["activeTargets"])

    def alerts(self) -> list[dict[str, Any]]:
        return list(self.api("alerts")["alerts"])
