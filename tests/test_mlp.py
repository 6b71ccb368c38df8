"""Small MLPs: scaling, splitting, Levenberg–Marquardt and first-order trainers (cnclab.analysis.mlp)."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from cnclab.analysis.mlp import MinMaxScaler, MLPSpec, split_indices, train_mlp


@settings(max_examples=40, deadline=None)
@given(arrays(np.float64, (7, 3), elements=st.floats(-1e3, 1e3)))
def test_scaler_round_trip(X):
    X = X + np.arange(7)[:, None]  # no constant column
    s = MinMaxScaler().fit(X)
    Z = s.transform(X)
    assert Z.min() >= -1 - 1e-12 and Z.max() <= 1 + 1e-12
    np.testing.assert_allclose(Z.min(axis=0), -1) and np.testing.assert_allclose(Z.max(axis=0), 1)
    np.testing.assert_allclose(s.inverse_transform(Z), X, atol=1e-9)


def test_scaler_rejects_constant_column():
    with pytest.raises(ValueError, match="constant"):
        MinMaxScaler().fit(np.array([[1.0, 2.0], [1.0, 3.0]]))


def test_split_is_a_deterministic_partition():
    tr, va, te = split_indices(2704, seed=7)
    assert (len(tr), len(va), len(te)) == (1893, 406, 405)
    assert np.array_equal(np.sort(np.concatenate([tr, va, te])), np.arange(2704))
    again = split_indices(2704, seed=7)
    assert all(np.array_equal(a, b) for a, b in zip((tr, va, te), again))
    assert not np.array_equal(tr, split_indices(2704, seed=8)[0])
    with pytest.raises(ValueError, match="fractions"):
        split_indices(10, fractions=(0.5, 0.5, 0.5))


def test_spec_parameter_counts():
    assert MLPSpec(4, (10,), 2).n_params == 4 * 10 + 10 + 10 * 2 + 2 == 72      # thesis a1
    assert MLPSpec(4, (10, 5), 2).n_params == 50 + 55 + 12 == 117               # thesis a2
    with pytest.raises(ValueError, match="activation"):
        MLPSpec(4, (10,), 2, activation="swish")


def _toy(n=300, seed=0):
    rng = np.random.default_rng(seed)
    X = rng.uniform(-2, 2, size=(n, 2))
    Y = np.column_stack([np.sin(X[:, 0]) * X[:, 1], np.cos(X[:, 1]) + 0.5 * X[:, 0]])
    return X, Y


def test_lm_learns_and_is_deterministic():
    X, Y = _toy()
    a = train_mlp(X, Y, hidden=(8,), seed=3, max_epochs=150)
    b = train_mlp(X, Y, hidden=(8,), seed=3, max_epochs=150)
    np.testing.assert_array_equal(a.theta, b.theta)           # same seed -> identical network
    te = a.split[2]
    rmse = np.sqrt(np.mean((a.predict(X[te]) - Y[te]) ** 2))
    assert rmse < 0.05 * Y.std()
    h = a.history
    assert h["train_mse"].iloc[a.best_epoch] < 0.01 * h["train_mse"].iloc[0]
    assert h["val_mse"].iloc[a.best_epoch] == h["val_mse"].min()   # returns best-validation weights
    c = train_mlp(X, Y, hidden=(8,), seed=4, max_epochs=150)
    assert not np.array_equal(a.theta, c.theta)


def test_two_hidden_layers_and_first_order_trainers():
    X, Y = _toy(200, seed=1)
    lm = train_mlp(X, Y, hidden=(6, 4), seed=0, max_epochs=100)
    assert lm.spec.n_params == len(lm.theta) == (2 + 1) * 6 + (6 + 1) * 4 + (4 + 1) * 2
    for trainer in ("adam", "lbfgs"):
        net = train_mlp(X, Y, hidden=(6,), trainer=trainer, seed=0, max_epochs=60, lr=0.02)
        h = net.history
        assert h["train_mse"].min() < 0.5 * h["train_mse"].iloc[0], trainer
        assert net.predict(X).shape == Y.shape


def test_early_stopping_counts_validation_failures():
    X, Y = _toy(120, seed=2)
    # heavy noise + a 10-neuron net on 84 training rows: LM overfits, validation error rises -> early stop
    noisy = Y + np.random.default_rng(0).normal(0, 0.5, Y.shape)
    for max_fail in (3, 5):
        net = train_mlp(X, noisy, hidden=(10,), seed=0, max_epochs=500, max_fail=max_fail)
        assert net.stop_reason == "validation_stop", net.stop_reason       # must stop early, not run out
        assert len(net.history) - 1 == net.best_epoch + max_fail        # exactly max_fail failures after the best
        assert net.history["val_mse"].iloc[net.best_epoch] == net.history["val_mse"].min()


@pytest.mark.parametrize("kw, word", [
    ({"trainer": "sgd"}, "trainer"), ({"max_epochs": 0}, "max_epochs"), ({"activation": "x"}, "activation")])
def test_bad_arguments(kw, word):
    X, Y = _toy(30)
    with pytest.raises(ValueError, match=word):
        train_mlp(X, Y, **kw)


def test_bad_shapes():
    with pytest.raises(ValueError, match="same n"):
        train_mlp(np.zeros((10, 2)), np.zeros((9, 1)))
    with pytest.raises(ValueError, match="finite"):
        train_mlp(np.full((10, 1), np.nan), np.zeros((10, 1)))


def test_init_is_matlab_initnw_by_hand():
    """MATLAB initnw/calcnw (mathworks.com/help/deeplearning/ref/initnw.html, the toolbox's initnw.m):
    hidden rows have norm 0.7·s^(1/r) × half the active range (logsig [-4, 4]: ×4), × 2/(hi−lo) of the
    input range (layer 2 sees logsig's [0, 1]: ×2); biases are 0.7·s^(1/r)·linspace(−1, 1, s)·sign(w₁)
    on the active scale (first layer, inputs in [-1, 1]); the linear output layer is rands in [-1, 1]."""
    import numpy as np
    from cnclab.analysis import mlp

    spec = mlp.MLPSpec(4, (10, 5), 2, "logsig")
    theta = mlp._init_params(spec, seed=3).numpy()
    W1, b1 = theta[:40].reshape(10, 4), theta[40:50]
    W2, b2 = theta[50:100].reshape(5, 10), theta[100:105]
    W3, b3 = theta[105:115].reshape(2, 5), theta[115:117]
    mag1, mag2 = 0.7 * 10 ** (1 / 4), 0.7 * 5 ** (1 / 10)
    assert np.allclose(np.linalg.norm(W1, axis=1), 4 * mag1)
    assert np.allclose(b1, 4 * mag1 * np.linspace(-1, 1, 10) * np.sign(W1[:, 0]))
    assert np.allclose(np.linalg.norm(W2, axis=1), 2 * 4 * mag2)
    # layer 2: b = 4·mag·linspace·sign(w) − Σ_j w_j (the [0, 1] input range mapped onto [-1, 1])
    assert np.allclose(b2, 4 * mag2 * np.linspace(-1, 1, 5) * np.sign(W2[:, 0]) - W2.sum(axis=1) / 2)
    assert np.all(np.abs(np.r_[W3.ravel(), b3]) <= 1.0)
