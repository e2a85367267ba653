"""`Parameters`: a joint's parameter set as a Python object, over the
parameter table (`src/hdjoint/parameter_table.def`, read through
`hdjoint.io.parameters`): defaults, units, descriptions, ranges, the
diagnosis's tolerances, and the JSON files `--params` reads."""
from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from html import escape

from hdjoint.io import parameters as table_io
from hdjoint.io.parameters import ParameterError, ParameterInfo

__all__ = ["Parameters", "ParameterError"]

PathLike = str | os.PathLike


class Parameters(Mapping[str, float]):
    """Every parameter of the joint, each at its default until set.

    A dict of name: value in SI units (read, set, iterate); the values a user
    set (or a file stated) are kept apart from the defaults, so a file
    written back holds only those, as a partial parameter file does.

    >>> p = Parameters()                       # the defaults
    >>> p.unit("Kt"), p["Kt"] == Parameters.defaults()["Kt"]
    ('N.m/A', True)
    >>> p["Kt"] = 0.05                        # checked against the table's range
    >>> p.stated
    {'Kt': 0.05}
    >>> p
    Parameters(Kt = 0.05 N.m/A; the other ... at their defaults)
    >>> p["Kt"] = -1.0
    Traceback (most recent call last):
    ...
    hdjoint.io.parameters.ParameterError: parameter set: parameter 'Kt' = -1.0 is outside its valid range ...
    """

    def __init__(self, values: Mapping[str, float] | None = None, *, tolerance: Mapping[str, float] | None = None,
                 accuracy: float | None = None, sensor_noise: Mapping[str, float] | None = None):
        self._values: dict[str, float] = table_io.defaults()
        self._stated: dict[str, float] = {}
        self.tolerance: dict[str, float] = table_io.check_tolerances(dict(tolerance or {}))
        """Relative tolerances (one standard deviation) overriding the diagnosis's priors."""
        self.accuracy: float | None = table_io.check_accuracy(accuracy)
        """The torque accuracy (N.m RMS) the diagnosis's verdict asks for; None: not stated."""
        self.sensor_noise: dict[str, float] = table_io.check_sensor_noise(dict(sensor_noise or {}))
        """Datasheet noise, RMS per recording column ("i_m" in A, "tau_sensor" in N.m)."""
        if values:
            self.update(values)

    # ------------------------------------------------------------------ construction

    @classmethod
    def defaults(cls) -> "Parameters":
        """The table's defaults (the paper's joint).

        >>> len(Parameters.defaults()) == len(Parameters.table())
        True
        """
        return cls()

    @classmethod
    def load(cls, path: PathLike) -> "Parameters":
        """A parameter file, as `--params` reads it: a partial file takes the
        defaults for the rest; "tolerance", "accuracy" and "sensor_noise" are
        kept; a documented file (`hdjoint params --defaults`) reads back the same.

        >>> import tempfile, os
        >>> path = os.path.join(tempfile.mkdtemp(), "joint.json")
        >>> Parameters({"Kt": 0.05}, tolerance={"Kt": 0.1}).save(path)
        >>> q = Parameters.load(path)
        >>> q.stated, q.tolerance
        ({'Kt': 0.05}, {'Kt': 0.1})
        """
        values = table_io.load(path)
        statements = table_io.load_statements(path)
        out = cls(tolerance=statements["tolerance"], accuracy=statements["accuracy"],
                  sensor_noise=statements["noise"])
        out._values = values
        out._stated = {name: values[name] for name in values if name in table_io.stated(path)}
        return out

    @classmethod
    def coerce(cls, params: "Parameters | Mapping[str, float] | PathLike | None") -> "Parameters":
        """PARAMS as Parameters: itself, a dict of name: value, a file's path, or None (the defaults)."""
        if params is None:
            return cls()
        if isinstance(params, Parameters):
            return params
        if isinstance(params, Mapping):
            return cls(params)
        return cls.load(params)

    def copy(self) -> "Parameters":
        out = Parameters(tolerance=self.tolerance, accuracy=self.accuracy, sensor_noise=self.sensor_noise)
        out._values, out._stated = dict(self._values), dict(self._stated)
        return out

    # ------------------------------------------------------------------ the mapping

    def __getitem__(self, name: str) -> float:
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __setitem__(self, name: str, value: float) -> None:
        self.update({name: value})

    def update(self, values: Mapping[str, float] = (), /, **more: float) -> None:
        """Set several values at once; each is checked against its range, and
        the set against the table's rules across parameters (encoder counts,
        delays). Nothing is set when one is refused."""
        given = {**dict(values), **more}
        checked = table_io.check({**self._values, **given})
        for name in given:
            self._values[name] = self._stated[name] = checked[name]

    def reset(self, name: str) -> None:
        """Back to the default, no longer stated."""
        self._values[name] = table_io.table()[name].default
        self._stated.pop(name, None)

    @property
    def stated(self) -> dict[str, float]:
        """The values set or read from a file (the rest are defaults): what `save` writes."""
        return dict(self._stated)

    def changed(self) -> dict[str, float]:
        """The values that differ from their defaults."""
        table = table_io.table()
        return {name: value for name, value in self._values.items() if value != table[name].default}

    def to_dict(self) -> dict[str, float]:
        """Every value, as a plain dict."""
        return dict(self._values)

    # ------------------------------------------------------------------ the table

    @staticmethod
    def table() -> dict[str, ParameterInfo]:
        """Every parameter's row: unit, default, range, scope, description, tolerance."""
        return table_io.table()

    def info(self, name: str) -> ParameterInfo:
        return table_io.table()[name]

    def unit(self, name: str) -> str:
        """The SI unit ("1" for a ratio)."""
        return self.info(name).unit

    def description(self, name: str) -> str:
        return self.info(name).description

    def range(self, name: str) -> tuple[float, float]:
        info = self.info(name)
        return info.min, info.max

    def in_text(self, name: str) -> str:
        """'Kt = 0.046 N.m/A': a value with its unit, as the findings say it."""
        return f"{name} = {self._values[name]:.4g}{table_io.unit_in_text(self.unit(name))}"

    # ------------------------------------------------------------------ files

    def file_content(self) -> dict:
        """What `save` writes: the stated values and statements, as `--params` reads them."""
        out: dict = dict(self._stated)
        if self.tolerance:
            out[table_io.TOLERANCE_KEY] = dict(self.tolerance)
        if self.accuracy is not None:
            out[table_io.ACCURACY_KEY] = self.accuracy
        if self.sensor_noise:
            out[table_io.SENSOR_NOISE_KEY] = dict(self.sensor_noise)
        return out

    def save(self, path: PathLike, *, documented: bool = False) -> None:
        """Write a parameter file `--params` reads: the stated values (a
        partial file), or with DOCUMENTED every value with its unit, range,
        description and the diagnosis's tolerance (`hdjoint params`)."""
        if documented:
            table_io.save_documented(path, self.to_dict(), self.tolerance, set(self._stated))
            return
        content = self.file_content()
        table_io.save(path, self._stated, {k: v for k, v in content.items() if k not in self._stated})

    # ------------------------------------------------------------------ display

    def __repr__(self) -> str:
        shown = [self.in_text(name) for name in self._stated]
        rest = len(self) - len(shown)
        if not shown:
            return f"Parameters(all {rest} at their defaults)"
        more = "; " + ", ".join(f"{k} = {v!r}" for k, v in (("tolerance", self.tolerance),
                                                            ("accuracy", self.accuracy),
                                                            ("sensor_noise", self.sensor_noise)) if v)
        return f"Parameters({', '.join(shown)}; the other {rest} at their defaults{more if more != '; ' else ''})"

    def _repr_html_(self) -> str:
        rows = []
        for name, info in table_io.table().items():
            value = self._values[name]
            style = ' style="font-weight:bold"' if name in self._stated else ""
            rows.append(f"<tr{style}><td><code>{escape(name)}</code></td><td>{value:.6g}</td>"
                        f"<td>{escape(info.unit)}</td><td>{info.default:.6g}</td>"
                        f"<td>{escape(info.description)}</td></tr>")
        return (f"<p>{escape(repr(self))}</p><table><tr><th>name</th><th>value</th><th>unit</th>"
                f"<th>default</th><th>description</th></tr>{''.join(rows)}</table>")

    def __eq__(self, other) -> bool:
        if isinstance(other, Parameters):
            return (self._values == other._values and self.tolerance == other.tolerance
                    and self.accuracy == other.accuracy and self.sensor_noise == other.sensor_noise)
        return Mapping.__eq__(self, other)

    __hash__ = None  # mutable
