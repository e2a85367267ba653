"""One recording's result as one flat row of fleet.parquet. The findings
document is read defensively: a field a diagnosis does not (yet) write
becomes NaN or empty here, never an error."""
from __future__ import annotations

import math

import pyarrow as pa

FINDING = pa.struct([("effect", pa.string()), ("kind", pa.string()), ("confidence", pa.float64()),
                     ("p_value", pa.float64())])
# Columns every row has, in this order; param.* and est.* columns follow (float64).
BASE_SCHEMA = pa.schema([
    ("recording", pa.string()), ("joint", pa.string()), ("date", pa.string()), ("command", pa.string()),
    ("key", pa.string()), ("status", pa.string()), ("verdict", pa.string()), ("findings", pa.list_(FINDING)),
    ("effects", pa.string()), ("seconds", pa.float64()), ("error", pa.string()), ("outputs", pa.string()),
])


def _float(x) -> float:
    if isinstance(x, bool):
        return float(x)
    try:
        return float(x)
    except (TypeError, ValueError):
        return math.nan


def findings_of(doc: dict) -> list[dict]:
    out = []
    for f in doc.get("findings") or []:
        if isinstance(f, dict) and f.get("effect"):
            out.append({"effect": str(f["effect"]), "kind": str(f.get("kind") or ""),
                        "confidence": _float(f.get("confidence")), "p_value": _float(f.get("p_value"))})
    return out


def _interval(entry) -> tuple[float, float, float, float]:
    """(estimate, lo, hi, tolerance) from a calibration or finding entry: a dict or a bare number."""
    if isinstance(entry, dict):
        value = entry.get("estimate", entry.get("calibrated", entry.get("value")))
        return _float(value), _float(entry.get("lo")), _float(entry.get("hi")), _float(entry.get("tolerance"))
    return _float(entry), math.nan, math.nan, math.nan


def parameter_columns(doc: dict) -> dict[str, float]:
    """param.<name>, param.<name>.lo, param.<name>.hi (and param.<name>.tol,
    the parameter's stated tolerance, where given) for the corrected set;
    intervals from the calibration, or from a finding that resized the parameter."""
    intervals = {}
    for f in doc.get("findings") or []:
        for name, entry in ((f or {}).get("parameters") or {}).items():
            intervals[name] = _interval(entry)
    for name, entry in (doc.get("calibration") or {}).items():
        intervals[name] = _interval(entry)
    cols = {}
    params = doc.get("params") or {}
    for name in dict.fromkeys(list(params) + list(intervals)):
        value, lo, hi, tol = intervals.get(name, (math.nan, math.nan, math.nan, math.nan))
        cols[f"param.{name}"] = _float(params.get(name, value))
        cols[f"param.{name}.lo"] = lo
        cols[f"param.{name}.hi"] = hi
        if math.isfinite(tol):
            cols[f"param.{name}.tol"] = tol
    return cols


def estimator_columns(doc: dict) -> dict[str, float]:
    """est.<label>.<estimate>.rms/max: the diagnosis' estimator comparison (against the sensor)."""
    cols = {}
    for label, figures in (doc.get("estimator") or {}).items():
        for name, fig in (figures or {}).items():
            if isinstance(fig, dict):
                cols[f"est.{label}.{name}.rms"] = _float(fig.get("rms"))
                cols[f"est.{label}.{name}.max"] = _float(fig.get("max"))
    return cols


def diagnosis_row(doc: dict) -> dict:
    found = findings_of(doc)
    return {"verdict": str(doc.get("verdict") or ""), "findings": found,
            "effects": ";".join(dict.fromkeys(f["effect"] for f in found)),
            **parameter_columns(doc), **estimator_columns(doc)}


def table(rows: list[dict]) -> pa.Table:
    """The rows as one table: the base columns, then every other column (float64) in first-seen order."""
    extra = list(dict.fromkeys(k for r in rows for k in r if k not in BASE_SCHEMA.names))
    schema = pa.schema(list(BASE_SCHEMA) + [(k, pa.float64()) for k in extra])
    columns = {}
    for field in schema:
        default = [] if field.name == "findings" else (math.nan if field.type == pa.float64() else None)
        columns[field.name] = [r.get(field.name, default) for r in rows]
    return pa.Table.from_pydict(columns, schema=schema)
