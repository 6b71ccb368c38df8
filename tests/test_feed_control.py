"""Feed control: MRR held at nominal where not capped, cap respected, time accounting."""
import numpy as np
import pytest

from cnclab.cutting.feed_control import controlled_feed, machining_time_s, mrr_error


def test_mrr_held_and_capped():
    ds = np.full(200, 0.05)
    w = np.r_[np.full(50, 1.5), np.linspace(1.5, 0.0, 100), np.full(50, 2.0)]
    eng = np.r_[np.full(50, 60.0), np.linspace(60, 0, 100), np.full(50, 90.0)]
    v = controlled_feed(w * ds, ds, eng, np.ones(200, bool), 1.5, 255.0, 1000.0, 60.0, block_mm=0.5)
    assert np.all(v <= 1000.0) and np.all(v[:50] == 255.0)
    mrr = 3 * w * v
    free = v < 1000.0
    assert np.allclose(mrr[free][50:], 3 * 1.5 * 255.0, rtol=0.15)
    assert np.all(v[-50:] < 255.0)                       # overshoot: slowed down
    assert np.isnan(controlled_feed(w * ds, ds, eng, np.zeros(200, bool), 1.5, 255, 1000, 60)).all()


def test_time_and_errors():
    assert machining_time_s([1.0, 2.0], [60.0, np.nan]) == pytest.approx(1.0)
    assert mrr_error([990.0, 1010.0], 1000.0)["mean_pct"] == pytest.approx(0.0)
    with pytest.raises(ValueError, match="v_fmax"):
        controlled_feed([0.1], [0.1], [60], [True], 1.5, 255.0, 100.0, 60.0)
    with pytest.raises(ValueError, match="same shape"):
        controlled_feed([0.1, 0.2], [0.1], [60], [True], 1.5, 255.0, 1000.0, 60.0)


def test_adjust_mask_only_changes_roll_segments():
    ds = np.full(60, 0.05)
    w = np.r_[np.full(20, 0.5), np.full(20, 1.5), np.full(20, 0.5)]      # removal width (mm)
    adj = np.r_[np.ones(20, bool), np.zeros(40, bool)]
    v = controlled_feed(w * ds, ds, np.full(60, 20.0), np.ones(60, bool), 1.5, 255.0, 1000.0, 60.0,
                        block_mm=0.5, adjust=adj)
    assert np.allclose(v[:20], 765.0) and np.all(v[20:] == 255.0)         # MRR held only in roll-in
    with pytest.raises(ValueError, match="adjust"):
        controlled_feed(w * ds, ds, np.full(60, 20.0), np.ones(60, bool), 1.5, 255.0, 1000.0, 60.0, adjust=adj[:5])


def test_windowed_mrr_error_hand_case():
    from cnclab.cutting.feed_control import mrr_error_windowed

    # 2 mm at nominal, 2 mm at +10 %: windows of 1 mm -> mean |e| = 5 %, signed mean 5 %
    rem = np.r_[np.full(20, 1.5), np.full(20, 1.65)] * 0.1
    r = mrr_error_windowed(rem, np.full(40, 0.1), np.full(40, 255.0), 3.0, 1147.5, window_mm=1.0)
    assert r["mean_abs_pct"] == pytest.approx(5.0) and r["mean_pct"] == pytest.approx(5.0) and r["n"] == 4
    assert mrr_error_windowed(rem, np.full(40, 0.1), np.full(40, 255.0), 3.0, 1147.5,
                              mask=np.zeros(40, bool))["n"] == 0
