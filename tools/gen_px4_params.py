#!/usr/bin/env python3
"""Generate ``operator/uavtest/px4/parameters_v1_15.json`` from PX4 v1.15's own facts.

Sources (read, never copied): PX4 v1.15's parameter metadata
``px4-params/px4-v1.15-sitl-parameters.json`` and the parameter sections (pyulog
``initial_parameters``) of the PX4 v1.15 SIH logs ``px4-sih/*.ulg`` in the shared data folder.

Usage: python3 tools/gen_px4_params.py [--data ../shared/data] [--out PATH] [--check]

Each entry: name → [type ("INT32" | "FLOAT"), PX4 default, SIH airframe value or null, min or
null, max or null, allowed values or null]. The SIH value is the one every log holds at boot;
where logs disagree, the one the real-time logs (``*-sf1``, ``square-mission``) agree on; else null.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
DEFAULT_DATA = REPO.parent / "shared" / "data"
DEFAULT_OUT = REPO / "operator" / "uavtest" / "px4" / "parameters_v1_15.json"
METADATA = "px4-params/px4-v1.15-sitl-parameters.json"
LOGS = "px4-sih/*.ulg"
COMMAND = "python3 tools/gen_px4_params.py"
_TYPES = {"Int32": "INT32", "Float": "FLOAT"}


def _real_time(log_name: str) -> bool:
    return log_name.endswith("-sf1.ulg") or log_name == "square-mission.ulg"


def sih_values(logs: Mapping[str, Mapping[str, float]]) -> dict[str, float]:
    """name → the SIH vehicle's boot value (see the module doc for disagreeing logs)."""
    names = sorted({n for values in logs.values() for n in values})
    out: dict[str, float] = {}
    for name in names:
        seen = {log: v[name] for log, v in logs.items() if name in v}
        distinct = set(seen.values())
        if len(distinct) > 1:
            distinct = {v for log, v in seen.items() if _real_time(log)}
        if len(distinct) == 1:
            out[name] = distinct.pop()
    return out


def _number(value: Any, ptype: str) -> int | float | None:
    if value is None:
        return None
    if ptype == "INT32":
        return int(value)
    return float(struct_f32(float(value)))


def struct_f32(value: float) -> float:
    """Round to float32 and back to the shortest float that prints the same (logs hold float32)."""
    import struct

    f32 = struct.unpack("<f", struct.pack("<f", value))[0]
    for digits in range(1, 18):
        short = float(f"{f32:.{digits}g}")
        if struct.unpack("<f", struct.pack("<f", short))[0] == f32:
            return short
    return f32


def build_table(metadata: Mapping[str, Any], logs: Mapping[str, Mapping[str, float]]) -> dict[str, list[Any]]:
    sih = sih_values(logs)
    table: dict[str, list[Any]] = {}
    for p in sorted(metadata["parameters"], key=lambda p: p["name"]):
        ptype = _TYPES[p["type"]]
        values = p.get("values")
        table[p["name"]] = [
            ptype,
            _number(p.get("default"), ptype),
            _number(sih.get(p["name"]), ptype),
            _number(p.get("min"), ptype) if ptype == "FLOAT" else p.get("min"),
            _number(p.get("max"), ptype) if ptype == "FLOAT" else p.get("max"),
            [int(v) for v in values] if values else None,
        ]
    return table


def render(metadata: Mapping[str, Any], table: Mapping[str, list[Any]], log_names: list[str]) -> str:
    header = {
        "generated": f"by `{COMMAND}`; do not edit",
        "px4": metadata.get("px4", "v1.15"),
        "sources": [METADATA, *(f"px4-sih/{n} (initial_parameters)" for n in log_names)],
        "columns": ["type", "default", "sih", "min", "max", "values"],
    }
    lines = ["{", f'  "_header": {json.dumps(header)},', '  "parameters": {']
    rows = [f"    {json.dumps(name)}: {json.dumps(row)}" for name, row in table.items()]
    lines.append(",\n".join(rows))
    lines.append("  }")
    lines.append("}")
    return "\n".join(lines) + "\n"


def read_logs(data: Path) -> dict[str, dict[str, float]]:
    from pyulog import ULog

    logs: dict[str, dict[str, float]] = {}
    for path in sorted(data.glob(LOGS)):
        logs[path.name] = dict(ULog(str(path), [], True).initial_parameters)
    return logs


def generate(data: Path) -> str:
    metadata = json.loads((data / METADATA).read_text())
    logs = read_logs(data)
    return render(metadata, build_table(metadata, logs), sorted(logs))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA, help="the shared data folder")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    parser.add_argument("--check", action="store_true", help="exit 1 when --out differs")
    args = parser.parse_args(argv)
    text = generate(args.data)
    if args.check:
        same = args.out.is_file() and args.out.read_text() == text
        print("up to date" if same else f"{args.out} differs from the sources; regenerate", file=sys.stderr)
        return 0 if same else 1
    args.out.write_text(text)
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
