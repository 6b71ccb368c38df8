"""The issue-29 pocket corpus (data/pockets/corpus) is what its generator says, frozen and traceable:
the committed jobs equal a fresh run of the seeded generator, every job loads, the families and the
cases named in the issue are there, every drawing job names its public source (repository, path,
commit, licence) and the committed copy of the drawing is byte-identical to it (git blob hash), and
FreeCAD's committed program and provenance exist for every job."""
import importlib.util
import json
from pathlib import Path

import pytest

from cnclab.paths import REPO_ROOT
from cnclab.works.jacso2021 import corpus_comparison as cc

# one xdist group (make test: --dist loadgroup): all of this module runs in one worker, so that
# the module-scoped `jobs` are loaded once
pytestmark = pytest.mark.xdist_group("test_corpus")

CORPUS = REPO_ROOT / "data" / "pockets" / "corpus"


def _generator():
    spec = importlib.util.spec_from_file_location("make_corpus", CORPUS / "make_corpus.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_corpus_is_the_frozen_generator_output():
    jobs = _generator().build()
    assert sorted(jobs) == cc.job_names() and len(jobs) >= 60
    for name, (d, _) in jobs.items():
        assert (CORPUS / f"{name}.json").read_text(encoding="utf-8") == json.dumps(d, indent=1) + "\n", name


@pytest.fixture(scope="module")
def jobs():
    """Every corpus job, loaded once for the tests below (cc.job reads and validates a file a call)."""
    return {n: cc.job(n) for n in cc.job_names()}


def test_families_named_cases_and_tools(jobs):
    fams = {n: cc.family(n) for n in cc.job_names()}
    assert {"star", "rectilinear", "islands", "neck", "slot_bulbs", "tapered_channel", "gear", "spiral", "comb",
            "channel_15d", "regions", "drawing"} == set(fams.values())
    assert sum(f == "drawing" for f in fams.values()) >= 10
    ch, g = jobs["tapered_channel_30_10"], jobs["gear10_island"]
    assert (ch.tool_diameter, ch.theta_deg, g.tool_diameter, g.theta_deg) == (8.0, 30.7, 6.0, 45.6)
    assert len(g.polygon.interiors) == 1                                  # the round island
    tools = {jobs[n].tool_diameter for n in cc.job_names()}
    thetas = [jobs[n].theta_deg for n in cc.job_names()]
    assert min(tools) == 3 and max(tools) == 12 and min(thetas) >= 20 and max(thetas) <= 120


@pytest.mark.parametrize("name", [n for n in cc.job_names() if n.startswith("dwg_")])
def test_drawing_provenance_and_fixture(name):
    prov = json.loads((CORPUS / "provenance" / f"{name}.json").read_text())
    assert {"repo", "path", "commit", "licence", "blob_sha1", "copy", "scale"} <= set(prov)
    gen = _generator()
    assert gen._blob_sha(REPO_ROOT / prov["copy"]) == prov["blob_sha1"]
    assert len(prov["commit"]) == 40 and prov["licence"]


def test_freecad_fixture_for_every_job(jobs):
    for name in cc.job_names():
        prov = json.loads((cc.FIXTURES / f"{name}.json").read_text())
        assert prov["job"] == f"data/pockets/corpus/{name}.json" and "plan_time_s" in prov
        assert Path(cc.FIXTURES / f"{name}.ngc").exists()
        assert prov["settings"]["tool_diameter"] == jobs[name].tool_diameter
