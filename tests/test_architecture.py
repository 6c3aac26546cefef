"""The package picture of docs/ARCHITECTURE.md, checked on the source: every workspace package a
module imports is declared in its package.xml, the declared dependencies have no cycle, no
runtime package imports ``qtree_benchmarks`` or ``scripts/``, and each node file stays short."""

from __future__ import annotations

import ast
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / 'ros2_ws' / 'src'
PACKAGES = sorted(p.name for p in SRC.iterdir() if (p / 'package.xml').is_file())
PYTHON_PACKAGES = [p for p in PACKAGES if (SRC / p / p).is_dir()]
SCRIPT_MODULES = {p.stem for p in (SRC.parents[1] / 'scripts').glob('*.py')}
BENCHMARKS = 'qtree_benchmarks'
NODE_FILE_MAX_LINES = 150


def declared(package: str, *, tests: bool = False) -> set[str]:
    """Workspace packages ``package`` declares (``depend``/``exec_depend``, plus test ones)."""
    tags = {'depend', 'exec_depend', 'build_depend'} | ({'test_depend'} if tests else set())
    root = ET.parse(SRC / package / 'package.xml').getroot()
    return {e.text.strip() for e in root if e.tag in tags and e.text} & set(PACKAGES)


def imported(paths: list[Path]) -> dict[str, set[str]]:
    """Top-level module names imported by each file (absolute imports only)."""
    found: dict[str, set[str]] = {}
    for path in paths:
        names: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names |= {a.name.split('.')[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names.add(node.module.split('.')[0])
        found[str(path.relative_to(SRC))] = names
    return found


def sources(package: str, *, tests: bool) -> list[Path]:
    root = SRC / package / ('test' if tests else package)
    return sorted(root.rglob('*.py')) if root.is_dir() else []


@pytest.mark.parametrize('package', PYTHON_PACKAGES)
def test_every_imported_workspace_package_is_declared(package: str) -> None:
    for tests in (False, True):
        allowed = declared(package, tests=tests) | {package}
        for path, names in imported(sources(package, tests=tests)).items():
            undeclared = (names & set(PACKAGES)) - allowed
            assert not undeclared, f'{path} imports {sorted(undeclared)}, not in package.xml'


@pytest.mark.parametrize('package', PYTHON_PACKAGES)
def test_no_import_from_scripts(package: str) -> None:
    for tests in (False, True):
        for path, names in imported(sources(package, tests=tests)).items():
            assert not names & SCRIPT_MODULES, f'{path} imports scripts/ {names & SCRIPT_MODULES}'


def test_runtime_packages_never_depend_on_the_benchmarks() -> None:
    for package in PACKAGES:
        if package != BENCHMARKS:
            assert BENCHMARKS not in declared(package, tests=True), package
            for path, names in imported(sources(package, tests=True)).items():
                assert BENCHMARKS not in names, path
            for path, names in imported(sources(package, tests=False)).items():
                assert BENCHMARKS not in names, path


def test_declared_dependencies_have_no_cycle() -> None:
    graph = {p: declared(p, tests=True) for p in PACKAGES}
    state: dict[str, int] = {}

    def visit(package: str, trail: tuple[str, ...]) -> None:
        if state.get(package) == 2:
            return
        assert state.get(package) != 1, f'dependency cycle: {" -> ".join((*trail, package))}'
        state[package] = 1
        for dependency in sorted(graph[package]):
            visit(dependency, (*trail, package))
        state[package] = 2

    for package in PACKAGES:
        visit(package, ())


def test_node_files_stay_short() -> None:
    for path in SRC.glob('*/*/*_node.py'):
        lines = len(path.read_text().splitlines())
        assert lines <= NODE_FILE_MAX_LINES, f'{path.name}: {lines} lines'


def test_scripts_are_thin_entry_points() -> None:
    for path in (SRC.parents[1] / 'scripts').glob('*.py'):
        lines = len(path.read_text().splitlines())
        assert lines <= 100, f'scripts/{path.name}: {lines} lines'


KEYWORD_ONLY_TYPES = [
    ('qtree_task_planner.blocker_search', 'BlockerSearchConfig'),
    ('qtree_task_planner.blocker_search', 'BlockerSearchResult'),
    ('qtree_task_planner.training', 'TrainingConfig'),
    ('qtree_task_planner.training', 'TrainingResult'),
    ('stpik_motion_planner.config', 'PlannerConfig'),
    ('stpik_motion_planner.execution_config', 'ExecutionConfig'),
    ('stpik_motion_planner.verifier', 'VerificationReport'),
]


@pytest.mark.parametrize(('module', 'name'), KEYWORD_ONLY_TYPES)
def test_config_and_result_types_are_built_by_keyword(module: str, name: str) -> None:
    """#27 item 3: every field of a config or result type is passed by name."""
    import importlib
    import inspect

    cls = getattr(importlib.import_module(module), name)
    parameters = list(inspect.signature(cls).parameters.values())
    assert parameters and all(p.kind is p.KEYWORD_ONLY for p in parameters)


def test_plan_results_take_only_the_answer_positionally() -> None:
    """PlanResult: (feasible, reason, message) positionally, everything after by keyword."""
    import inspect

    from stpik_motion_planner.result import PlanResult

    kinds = [p.kind for p in inspect.signature(PlanResult).parameters.values()]
    assert kinds[:3] == [inspect.Parameter.POSITIONAL_OR_KEYWORD] * 3
    assert all(k is inspect.Parameter.KEYWORD_ONLY for k in kinds[3:]) and len(kinds) > 10
