"""The package reads top-down: its layers import downwards only (README, "Layout"), there are no
import cycles between rollplan's modules, and no module imports another module's private names.
Checked on the source (ast), and by importing every module in a fresh interpreter in dependency order."""

import ast
import functools
import json
import subprocess
import sys
from graphlib import CycleError, TopologicalSorter
from pathlib import Path

import pytest
from conftest import package_nodes, package_tree

import rollplan

PACKAGE = Path(rollplan.__file__).resolve().parent


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


@functools.cache
def _tree(name: str) -> ast.Module:
    """The syntax tree of a module's source, parsed once per process (the checks only read it)."""
    return package_tree(MODULES[name])


@functools.cache
def _imports(name: str) -> tuple:
    """``(target module, imported name or None, line)`` of every import statement of a module, at any
    depth (imports inside functions count too), relative imports resolved; found once per process."""
    path = MODULES[name]
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    return tuple(_imports_of(_tree(name), package))


def _imports_of(tree, package):
    """``(target module, imported name or None, line)`` of every import statement of a syntax tree, relative
    imports resolved against ``package`` (a list of name parts)."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, None, node.lineno
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            for alias in node.names:
                yield target, alias.name, node.lineno


@functools.cache
def _graph() -> dict:
    """Module -> the rollplan modules it imports (a ``from X import y`` of a submodule y counts as X.y); made
    once per process: do not change it."""
    graph = {}
    for name in MODULES:
        deps = set()
        for target, item, _ in _imports(name):
            if item is not None and f"{target}.{item}" in MODULES:
                deps.add(f"{target}.{item}")
            elif target in MODULES:
                deps.add(target)
        deps.discard(name)
        graph[name] = deps
    return graph


def test_every_module_is_found():
    assert {"rollplan", "rollplan.problem", "rollplan.result", "rollplan.core.model", "rollplan.cli",
            "rollplan.planners.geometric.planner", "rollplan.planners.collocation.transcription",
            "rollplan.studies.paper.stages", "rollplan.plots.paper"} <= set(MODULES)


@pytest.mark.slow
def test_no_module_imports_another_modules_private_names():
    bad = [f"{MODULES[name].relative_to(PACKAGE.parent)}:{line}: from {target} import {item}"
           for name in MODULES for target, item, line in _imports(name)
           if item is not None and item.startswith("_") and not item.startswith("__")
           and target != name and (target in MODULES or target.startswith("rollplan."))]
    assert not bad, "private names imported across modules:\n" + "\n".join(bad)


#: The layers of the package, bottom first (README, "Layout"): a module imports modules of its own layer
#: or of a lower one only. Keys are the first component under ``rollplan`` (``""`` is the package itself).
LAYERS = (
    {"", "version", "errors", "interrupts", "progress", "threads", "inputs", "outputs"},  # foundations
    {"core"},  # the model, curves, integrators, compiled functions
    {"robot", "problem", "result", "timeseries", "measures", "waypoints"},  # the problem statement and the result types
    {"planners"},
    {"execution"},  # timing, actuation, plants, feedback
    {"codegen", "io"},  # generated C; JSON forms of results and plan files
    {"plots"},  # figures of results
    {"studies"},  # paper reproduction, atlas, batch, comparison
    {"cli"},
)


def _layer(module: str) -> int:
    parts = module.split(".")
    key = parts[1] if len(parts) > 1 else ""
    ranks = [i for i, layer in enumerate(LAYERS) if key in layer]
    assert len(ranks) == 1, f"{module}: in no layer or in several of tests/test_layout.py's LAYERS"
    return ranks[0]


def test_layers_import_downwards_only():
    upward = [f"{MODULES[name].relative_to(PACKAGE.parent)} imports {dep}"
              for name, deps in _graph().items() for dep in sorted(deps) if _layer(dep) > _layer(name)]
    assert not upward, "imports from a higher layer:\n" + "\n".join(upward)


#: Modules that run code of a higher layer in a subprocess (invisible to the import graph), each with the
#: module it runs: none (the geometric planner builds its C search in its own process, below the code generator).
SUBPROCESS_IMPORTS = set()


def _string(node):
    """The text of a string literal; an f-string's replacement fields read as a name."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.JoinedStr):
        return "".join(part.value if isinstance(part, ast.Constant) else "_" for part in node.values)
    return None


def test_no_hidden_upward_dependency_through_code_in_strings():
    """Code written into a string and run elsewhere (``python -c``) imports too: an upward import there is
    listed in SUBPROCESS_IMPORTS, or it is an error."""
    found = set()
    for name, path in MODULES.items():
        for node in package_nodes(path):
            text = _string(node)
            if text is not None and "import" in text:
                try:
                    tree = ast.parse(text)
                except SyntaxError:
                    continue
                for target, _, _ in _imports_of(tree, name.split(".")):
                    if target and target.startswith("rollplan") and _layer(target) > _layer(name):
                        found.add((name, target))
    assert found == SUBPROCESS_IMPORTS


def test_import_graph_has_no_cycles():
    graph = _graph()
    try:
        tuple(TopologicalSorter(graph).static_order())
    except CycleError as exc:
        pytest.fail(f"import cycle: {' -> '.join(exc.args[1])}")


@pytest.mark.slow
def test_modules_import_in_dependency_order_in_a_fresh_interpreter():
    order = list(TopologicalSorter(_graph()).static_order())
    code = "import importlib, sys\nfor m in sys.argv[1:]:\n    importlib.import_module(m)\n"
    run = subprocess.run([sys.executable, "-c", code, *order], check=False, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr


def _fresh(code: str) -> str:
    """Run ``code`` in a fresh interpreter: its stdout; fails with its stderr."""
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 0, run.stderr
    return run.stdout


@pytest.fixture(scope="module")
def loaded():
    """What a fresh interpreter has loaded (scipy, and the heavy modules a plan does not need) after importing
    rollplan and its command, after a plan by the Python API, and after the `rollplan plan` command: one
    process for the tests that read it."""
    out = _fresh("import json, sys, rollplan, rollplan.cli\n"
                 "HEAVY = ('matplotlib', 'rollplan.planners.collocation', 'rollplan.plots', 'rollplan.studies',\n"
                 "         'scipy')\n"
                 "def heavy():\n"
                 "    return [m for m in sys.modules if m.startswith(HEAVY)]\n"
                 "seen = {'import': heavy()}\n"
                 "p = rollplan.plan((1, -0.5, 1), steps=3, k=2.5)\n"
                 "assert p.certificate.passed\n"
                 "seen['plan'] = heavy()\n"
                 "code = rollplan.cli.main(['plan', '--to', '1', '-0.5', '--psi', '1', '--steps', '3', '--k', '2.5'])\n"
                 "seen['command'] = heavy()\n"
                 "print(json.dumps([code, seen]))\n")
    code, seen = json.loads(out.splitlines()[-1])
    assert code == 0
    return seen


def test_no_runtime_path_imports_scipy(loaded):
    """scipy is a test dependency only: importing rollplan and its command, and planning, load no scipy."""
    assert not [m for m in loaded["import"] + loaded["plan"] if m.startswith("scipy")]
    _fresh("import sys\n"
           "sys.modules['scipy'] = None   # as if scipy were not installed: importing it fails\n"
           "import rollplan.cli\n"
           "assert rollplan.cli.main(['plan', '--to', '0.5', '0.3', '--psi', '0.4', '--steps', '2']) == 0\n")


def test_a_plan_loads_neither_collocation_nor_plots(loaded):
    """The `rollplan plan` command loads what a plan uses (lazy imports), not the other planners or plots (nor
    does importing rollplan or a plan by the Python API before it)."""
    assert not loaded["command"], loaded["command"]


def test_lazy_names_resolve():
    """Every name rollplan exports resolves (imported on first use), and an unknown name is an AttributeError."""
    for name in rollplan.__all__:
        assert getattr(rollplan, name) is not None and name in dir(rollplan)
    with pytest.raises(AttributeError):
        rollplan.no_such_name  # noqa: B018
    from rollplan.planners import METHODS

    assert set(METHODS) == {"geometric", "collocation", "rest_to_rest", "minimum_time"}
    assert METHODS["geometric"].__name__ == "ComposedPlanner"
