"""The package is layered, and imports run one way: from the application down
to the C++ core. Every import is read, including those inside functions, so
a circle cannot hide behind a lazy import."""
import ast
from pathlib import Path

import hdjoint

PACKAGE = Path(hdjoint.__file__).resolve().parent
# Bottom to top. A module may import its own layer and the layers below it.
LAYERS = ("hdjoint._core", "hdjoint.io", "hdjoint.fmu", "hdjoint.estimation", "hdjoint.diagnosis",
          "hdjoint.jobs", "hdjoint.fleet", "hdjoint.api", "hdjoint.app")
# Helpers of the tests and benchmarks, never shipped.
NOT_SHIPPED = ("truth", "tuning")


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in PACKAGE.rglob("*.py")}


def _resolve(name: str, known: dict[str, Path]) -> str:
    """The module NAME refers to: itself, or its package when NAME is a
    function or class imported from a module."""
    while name not in known and "." in name:
        name = name.rsplit(".", 1)[0]
    return name


def imports_of(module: str, path: Path, known: dict[str, Path]) -> set[str]:
    """Every hdjoint module MODULE imports, anywhere in its file."""
    is_package = path.name == "__init__.py"
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = module.split(".") if is_package else module.split(".")[:-1]
                parts = parts[: len(parts) - node.level + 1]
                base = ".".join(parts + ([node.module] if node.module else []))
            names = [f"{base}.{a.name}" for a in node.names] if base else []
        else:
            continue
        for name in names:
            if name == "hdjoint" or name.startswith("hdjoint."):
                target = "hdjoint._core" if name.startswith("hdjoint._core") else _resolve(name, known)
                if target not in ("hdjoint", module):
                    found.add(target)
    return found


def _layer(module: str) -> int:
    return max(i for i, prefix in enumerate(LAYERS) if module == prefix or module.startswith(prefix + "."))


def _graph() -> dict[str, set[str]]:
    known = _modules()
    return {m: imports_of(m, p, known) for m, p in known.items() if m != "hdjoint"}


def test_every_module_sits_in_a_layer():
    for module in _graph():
        assert any(module == p or module.startswith(p + ".") for p in LAYERS), f"{module} is in no layer"


def test_no_import_reaches_up_a_layer():
    upward = [f"{m} imports {t}" for m, targets in _graph().items() for t in targets if _layer(t) > _layer(m)]
    assert not upward, "\n".join(upward)


def circles(graph: dict[str, set[str]]) -> list[str]:
    """Every import circle of `graph` (module -> modules it imports), as 'a -> b -> a'."""
    state: dict[str, int] = {}
    found = []

    def visit(node, trail):
        state[node] = 1
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                found.append(" -> ".join(trail[trail.index(nxt):] + [nxt]))
            elif nxt not in state:
                visit(nxt, trail + [nxt])
        state[node] = 2

    for module in sorted(graph):
        if module not in state:
            visit(module, [module])
    return found


def test_no_import_circles():
    assert not circles(_graph())


def test_the_demo_does_not_import_the_command_line():
    assert "hdjoint.app.cli" not in _graph()["hdjoint.app.demo"]


def test_test_helpers_are_not_shipped():
    shipped = {p.stem for p in PACKAGE.rglob("*.py")} | {p.name for p in PACKAGE.rglob("*") if p.is_dir()}
    assert not shipped & set(NOT_SHIPPED)


def test_the_checker_sees_an_import_inside_a_function(tmp_path):
    """The test itself: a lazy import back up a layer is found."""
    source = tmp_path / "hdjoint" / "io" / "sneaky.py"
    source.parent.mkdir(parents=True)
    source.write_text("def f():\n    from hdjoint.diagnosis.pipeline import diagnose\n    from ..app import cli\n")
    known = {"hdjoint.io.sneaky": source, "hdjoint.diagnosis.pipeline": source, "hdjoint.app.cli": source}
    found = imports_of("hdjoint.io.sneaky", source, known)
    assert found == {"hdjoint.diagnosis.pipeline", "hdjoint.app.cli"}
    assert all(_layer(t) > _layer("hdjoint.io.sneaky") for t in found)


def test_one_conftest_for_the_whole_suite():
    # Test modules import shared names with `from conftest import ...`; a
    # second conftest.py in a subfolder would shadow the root one for the
    # whole session and break those imports whenever both are collected.
    tests = Path(__file__).resolve().parents[1]
    assert [p.relative_to(tests).as_posix() for p in tests.rglob("conftest.py")] == ["conftest.py"]


def test_the_architecture_page_names_every_module():
    """docs/architecture.md is where a newcomer finds a module's job: each one is named there."""
    page = (Path(__file__).resolve().parents[2] / "docs" / "architecture.md").read_text()
    missing = sorted(m for m in _graph() if not m.endswith("._core") and m.count(".") >= 2 and
                     not (PACKAGE / m.split(".", 1)[1].replace(".", "/")).is_dir() and f"`{m.rsplit('.', 1)[1]}`" not in page)
    assert not missing, f"docs/architecture.md does not name: {missing}"


def test_the_benchmarks_have_no_circles_and_share_no_private_names():
    """Benchmarks import each other one way and only public names (the stamp, the LARA8
    conventions and the independent truth are modules of their own)."""
    folder = Path(__file__).resolve().parents[2] / "benchmarks"
    scripts = {p.stem: p for p in folder.glob("*.py")}
    graph, private = {}, []
    for name, path in scripts.items():
        graph[name] = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                graph[name] |= {a.name for a in node.names if a.name in scripts}
            elif isinstance(node, ast.ImportFrom) and node.module in scripts:
                graph[name].add(node.module)
                private += [f"{name} imports {node.module}.{a.name}" for a in node.names if a.name.startswith("_")]
            elif isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.attr.startswith("_") \
                    and node.value.id in ("independent", *scripts) and not node.attr.startswith("__"):
                private.append(f"{name} reads {node.value.id}.{node.attr}")
    assert not private, private
    assert not circles(graph)


# The diagnosis's stages, bottom to top; a stage imports its own and those below it, the
# shared base (rules, normal, forked) and the effects. The effects are plug-ins: they may use
# the model's signals (kinematics, structure), which in turn evaluate them.
DIAGNOSIS = "hdjoint.diagnosis"
STAGES = ("model", "fit", "search", "verdict", "output")
DIAGNOSIS_BASE = ("rules", "normal", "forked")


def _stage(module: str) -> int | None:
    """A diagnosis module's rank: base 0, stages 1-5, effects 1, pipeline/results/facade on top."""
    rest = module[len(DIAGNOSIS) + 1:].split(".")
    if rest[0] in DIAGNOSIS_BASE:
        return 0
    if rest[0] == "effects":
        return 1
    if rest[0] in STAGES:
        return 1 + STAGES.index(rest[0])
    return len(STAGES) + 1


def test_diagnosis_stages_import_downward():
    upward = [f"{m} imports {t}" for m, targets in _graph().items() if m.startswith(DIAGNOSIS + ".")
              for t in targets if t.startswith(DIAGNOSIS + ".") and _stage(t) > _stage(m)
              and not (m.startswith(DIAGNOSIS + ".effects") and t.startswith(DIAGNOSIS + ".model."))]
    assert not upward, "\n".join(upward)


def test_upper_layers_use_the_diagnosis_facade():
    """jobs, fleet and app name only `hdjoint.diagnosis`, never a stage's module, so that the stages
    can move without touching them."""
    reaching_in = [f"{m} imports {t}" for m, targets in _graph().items() if _layer(m) > LAYERS.index(DIAGNOSIS)
                   for t in targets if t.startswith(DIAGNOSIS + ".")]
    assert not reaching_in, "\n".join(reaching_in)


def test_every_facade_name_resolves():
    import hdjoint.diagnosis as facade
    for name in facade.__all__:
        assert getattr(facade, name) is not None, name
