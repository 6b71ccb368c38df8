"""``python -m cnclab warm``: its parts and its arguments (the compiling itself runs first in every
``make test``/``make reproduce``)."""
import pytest

from cnclab import warm


def test_every_part_has_a_warmer_and_a_bad_part_is_named():
    assert set(warm.PARTS) == set(warm._WARMERS)
    with pytest.raises(ValueError, match="'solver'"):
        warm.warm_part("solver")


def test_jobs_below_one_is_refused(capsys):
    with pytest.raises(SystemExit) as e:
        warm.main(["--jobs", "0"])
    assert e.value.code == 2 and "--jobs must be >= 1, got 0" in capsys.readouterr().err
