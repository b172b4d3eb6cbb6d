"""The package as a user meets it: stubs that match the module, a docstring
on everything, the docstring examples and the README's example."""

import ast
import doctest
import inspect
import pathlib
import re

import pytest

import pcaline
from pcaline import _pcaline

STUB = pathlib.Path(__file__).resolve().parents[1] / "pcaline" / "_pcaline.pyi"


def stub_members() -> dict:
    """Top-level names of the stub, and each class's methods/properties."""
    tree = ast.parse(STUB.read_text())
    members = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            members[node.name] = {
                n.name for n in node.body if isinstance(n, ast.FunctionDef)
            }
        elif isinstance(node, ast.FunctionDef):
            members[node.name] = None
    return members


def public(names):
    return {n for n in names if not n.startswith("__")}


def test_the_stubs_cover_the_module_exactly():
    stubs = stub_members()
    module = {n for n in dir(_pcaline) if not n.startswith("__")}
    assert module == set(stubs), "classes and functions"
    for name, methods in stubs.items():
        obj = getattr(_pcaline, name)
        if methods is None or not inspect.isclass(obj) or issubclass(obj, Exception):
            continue
        own = {n for n, _ in inspect.getmembers(obj) if n in obj.__dict__}
        assert public(own) == public(methods), name


def test_everything_public_has_a_docstring():
    for name in dir(_pcaline):
        if name.startswith("__"):
            continue
        obj = getattr(_pcaline, name)
        assert obj.__doc__ and obj.__doc__.strip(), name
        if inspect.isclass(obj) and not issubclass(obj, Exception):
            for member, value in obj.__dict__.items():
                if member.startswith("__"):
                    continue
                assert getattr(value, "__doc__", None), f"{name}.{member}"


@pytest.mark.parametrize("module", [pcaline, pcaline.sim, pcaline.eval])
def test_docstring_examples_run(module):
    result = doctest.testmod(module, raise_on_error=False)
    assert result.attempted > 0 and result.failed == 0


def test_the_readme_example_runs(root, data, tmp_path, monkeypatch):
    """The README's Python example, with the plot written to a file."""
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    readme = (root / "README.md").read_text()
    block = re.search(r"## Python.*?```python\n(.*?)```", readme, re.S)
    assert block, "README: no Python example"
    code = block.group(1).replace('"../shared/data/', f'"{data}/')
    assert len(code.strip().splitlines()) <= 12
    monkeypatch.chdir(root)
    import matplotlib.pyplot as plt

    monkeypatch.setattr(plt, "show", lambda: plt.savefig(tmp_path / "lines.png"))
    exec(compile(code, "README.md", "exec"), {})
    assert (tmp_path / "lines.png").stat().st_size > 1000
