"""make reproduce's notebook keys: each notebook depends on the cnclab modules it imports (transitively)
and the data they name, not on unrelated recipes; a changed input changes only the dependent keys."""
from cnclab import reproduce
from cnclab.paths import NOTEBOOKS_DIR, PACKAGE_DIR

NN = NOTEBOOKS_DIR / "mgherony2024" / "ch6_neural_networks.ipynb"
T1 = NOTEBOOKS_DIR / "jacso2021" / "thesis1_engagement_formulas.ipynb"


def test_dependencies_follow_imports():
    _, nn_files = reproduce.notebook_inputs(NN)
    _, t1_files = reproduce.notebook_inputs(T1)
    assert PACKAGE_DIR / "analysis" / "mlp.py" in nn_files
    assert PACKAGE_DIR / "analysis" / "mlp.py" not in t1_files
    assert PACKAGE_DIR / "toolpath" / "dropcutter.py" not in nn_files
    assert NN in nn_files and T1 in t1_files


def test_changed_module_changes_only_dependent_keys(monkeypatch):
    k_nn, _ = reproduce.notebook_inputs(NN)
    k_t1, _ = reproduce.notebook_inputs(T1)
    mlp = PACKAGE_DIR / "analysis" / "mlp.py"
    real = reproduce._bytes
    monkeypatch.setattr(reproduce, "_bytes", lambda p: real(p) + (b"# edited\n" if p == mlp else b""))
    assert reproduce.notebook_inputs(NN)[0] != k_nn
    assert reproduce.notebook_inputs(T1)[0] == k_t1


def test_imports_parsed_from_cells():
    src = "%matplotlib inline\nimport numpy as np\nfrom cnclab.works.mgherony2024 import ch6\nimport cnclab.sweep\n"
    assert reproduce._cnclab_imports(src) == {"cnclab.works.mgherony2024", "cnclab.works.mgherony2024.ch6",
                                              "cnclab.sweep"}
