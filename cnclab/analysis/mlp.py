"""Small multilayer perceptrons for regression, trained by Levenberg–Marquardt or a first-order method.

The networks of Mgherony (2024) §6.3.2 were built with MATLAB's Neural Network Toolbox: inputs and
targets min-max scaled to [-1, 1] (``mapminmax``), a random 70/15/15 train/validation/test split
(``dividerand``), logistic-sigmoid hidden layers, a linear output layer, and training by
Levenberg–Marquardt (``trainlm``: μ = 0.001, ×0.1 after a successful step, ×10 after a failed one,
μ_max = 1e10, early stop after 6 consecutive validation failures, at most 1000 epochs). This module
reproduces that recipe with torch (imported lazily, only here), in float64 on the CPU, with one
thread, deterministic for a given ``seed``.

* :func:`train_mlp` — scale, split, build, train; returns a :class:`TrainedMLP` (``predict`` in the
  original units).
* trainers: ``"lm"`` (Levenberg–Marquardt with the full Jacobian, per-sample ``torch.func``
  Jacobians: the nets are tiny), ``"adam"`` and ``"lbfgs"`` (first order / quasi-Newton, full batch).

>>> import numpy as np
>>> x = np.linspace(-1, 1, 200)[:, None]
>>> net = train_mlp(x, np.sin(3 * x), hidden=(8,), seed=0, max_epochs=200)
>>> bool(np.sqrt(np.mean((net.predict(x) - np.sin(3 * x)) ** 2)) < 0.01)
True
"""
from __future__ import annotations

import dataclasses
from typing import Sequence

import numpy as np
import pandas as pd

__all__ = ["MinMaxScaler", "split_indices", "MLPSpec", "TrainedMLP", "TrainConfig", "train_mlp", "ACTIVATIONS"]

ACTIVATIONS = ("logsig", "tansig", "relu")
TRAINERS = ("lm", "adam", "lbfgs")


def _torch():
    import torch

    torch.set_num_threads(1)
    return torch


@dataclasses.dataclass
class MinMaxScaler:
    """Column-wise affine map of ``[min, max]`` onto ``[lo, hi]`` (MATLAB ``mapminmax``: [-1, 1])."""

    lo: float = -1.0
    hi: float = 1.0
    data_min: np.ndarray | None = None
    data_max: np.ndarray | None = None

    def fit(self, X) -> "MinMaxScaler":
        X = np.asarray(X, dtype=float)
        if X.ndim != 2 or len(X) == 0:
            raise ValueError(f"X must be a non-empty 2-D array, got shape {X.shape}")
        self.data_min, self.data_max = X.min(axis=0), X.max(axis=0)
        flat = np.flatnonzero(self.data_max <= self.data_min)
        if flat.size:
            raise ValueError(f"column(s) {flat.tolist()} are constant: cannot min-max scale")
        return self

    def transform(self, X) -> np.ndarray:
        X = np.asarray(X, dtype=float)
        return self.lo + (self.hi - self.lo) * (X - self.data_min) / (self.data_max - self.data_min)

    def inverse_transform(self, Z) -> np.ndarray:
        Z = np.asarray(Z, dtype=float)
        return self.data_min + (Z - self.lo) * (self.data_max - self.data_min) / (self.hi - self.lo)


def split_indices(n: int, fractions=(0.70, 0.15, 0.15), seed: int = 0):
    """Random train/validation/test index arrays (``dividerand``): sizes round(f·n), the rest to test.

    >>> [len(a) for a in split_indices(2704, seed=1)]
    [1893, 406, 405]
    """
    f = np.asarray(fractions, dtype=float)
    if f.shape != (3,) or np.any(f < 0) or not np.isclose(f.sum(), 1.0):
        raise ValueError(f"fractions must be three non-negative numbers summing to 1, got {fractions}")
    if n < 3:
        raise ValueError(f"n must be >= 3, got {n}")
    perm = np.random.default_rng(seed).permutation(n)
    n_tr, n_va = int(round(f[0] * n)), int(round(f[1] * n))
    return np.sort(perm[:n_tr]), np.sort(perm[n_tr:n_tr + n_va]), np.sort(perm[n_tr + n_va:])


@dataclasses.dataclass(frozen=True)
class MLPSpec:
    """Layer sizes and hidden activation; the output layer is linear."""

    n_inputs: int
    hidden: tuple
    n_outputs: int
    activation: str = "logsig"

    def __post_init__(self):
        if self.activation not in ACTIVATIONS:
            raise ValueError(f"activation must be one of {ACTIVATIONS}, got {self.activation!r}")
        if self.n_inputs < 1 or self.n_outputs < 1 or any(int(h) < 1 for h in self.hidden):
            raise ValueError(f"layer sizes must be >= 1, got {self.n_inputs}, {self.hidden}, {self.n_outputs}")

    @property
    def sizes(self) -> list[int]:
        return [self.n_inputs, *map(int, self.hidden), self.n_outputs]

    @property
    def n_params(self) -> int:
        s = self.sizes
        return sum((a + 1) * b for a, b in zip(s[:-1], s[1:]))

    def name(self) -> str:
        return "-".join(map(str, self.sizes)) + f" ({self.activation})"


#: MATLAB transfer functions' ranges (Neural Network Toolbox): ``'active'`` input range used by
#: ``initnw`` and the ``'output'`` range a following layer sees as its input range
ACTIVE_RANGE = {"logsig": (-4.0, 4.0), "tansig": (-2.0, 2.0)}
OUTPUT_RANGE = {"logsig": (0.0, 1.0), "tansig": (-1.0, 1.0)}


def _rands(g, *shape):
    """MATLAB ``rands``: uniform on [-1, 1]."""
    torch = _torch()
    return torch.rand(*shape, generator=g, dtype=torch.float64) * 2 - 1


def _calcnw(g, n_in: int, s: int, in_range, active):
    """MATLAB ``initnw``'s ``calcnw`` for one layer of ``s`` neurons with ``n_in`` inputs ranging over
    ``in_range`` (lo, hi) and a transfer function whose active input range is ``active``:
    w = 0.7 s^(1/r) · normr(rands(s, r)); b = 0.7 s^(1/r) · linspace(-1, 1, s) · sign(w[:, 0]);
    both scaled to the active range, then the input range mapped onto [-1, 1]."""
    torch = _torch()
    mag = 0.7 * s ** (1.0 / n_in)
    w = _rands(g, s, n_in)
    w = mag * w / w.norm(dim=1, keepdim=True)
    b = (torch.zeros(s, dtype=torch.float64) if s == 1
         else mag * torch.linspace(-1.0, 1.0, s, dtype=torch.float64) * torch.sign(w[:, 0]))
    x, y = 0.5 * (active[1] - active[0]), 0.5 * (active[1] + active[0])
    w, b = x * w, x * b + y
    lo, hi = in_range
    xi = 2.0 / (hi - lo)
    b = w @ torch.full((n_in,), 1.0 - hi * xi, dtype=torch.float64) + b
    return w * xi, b


def _init_params(spec: MLPSpec, seed: int):
    """MATLAB's default initialisation of a ``feedforwardnet``/``fitnet`` (``initlay`` calling ``initnw``
    on every layer; documentation: https://mathworks.com/help/deeplearning/ref/initnw.html and the
    toolbox's ``initnw.m``): each hidden layer by Nguyen–Widrow (:func:`_calcnw`) with its transfer
    function's active range (``ACTIVE_RANGE``) and its input range — [-1, 1] after ``mapminmax`` for
    the first layer, the previous layer's output range (``OUTPUT_RANGE``: [0, 1] for logsig) after
    that; the linear output layer (``purelin``, infinite active range) by ``rands`` (uniform [-1, 1]),
    as ``initnw`` falls back to. ``relu`` (no finite active range) is initialised by ``rands`` too."""
    torch = _torch()
    g = torch.Generator().manual_seed(int(seed))
    parts = []
    sizes = spec.sizes
    in_range = (-1.0, 1.0)
    for li, (n_in, n_out) in enumerate(zip(sizes[:-1], sizes[1:])):
        hidden = li < len(sizes) - 2
        if hidden and spec.activation in ACTIVE_RANGE:
            W, b = _calcnw(g, n_in, n_out, in_range, ACTIVE_RANGE[spec.activation])
            in_range = OUTPUT_RANGE[spec.activation]
        else:
            W, b = _rands(g, n_out, n_in), _rands(g, n_out)
            in_range = (-1.0, 1.0)
        parts += [W.reshape(-1), b]
    return torch.cat(parts)


def _forward(theta, X, spec: MLPSpec):
    """Network output for a flat parameter vector ``theta`` (torch); X is (n, n_inputs) or (n_inputs,)."""
    torch = _torch()
    act = {"logsig": torch.sigmoid, "tansig": torch.tanh, "relu": torch.relu}[spec.activation]
    h, k = X, 0
    sizes = spec.sizes
    for li, (n_in, n_out) in enumerate(zip(sizes[:-1], sizes[1:])):
        W = theta[k:k + n_in * n_out].reshape(n_out, n_in)
        k += n_in * n_out
        b = theta[k:k + n_out]
        k += n_out
        h = h @ W.T + b
        if li < len(sizes) - 2:
            h = act(h)
    return h


@dataclasses.dataclass
class TrainedMLP:
    """A trained network with its scalers, split, training history and stop reason."""

    spec: MLPSpec
    theta: np.ndarray
    x_scaler: MinMaxScaler
    y_scaler: MinMaxScaler
    split: tuple
    history: pd.DataFrame
    best_epoch: int
    stop_reason: str
    trainer: str
    seed: int

    def predict(self, X) -> np.ndarray:
        """Outputs in the original units for inputs ``X`` (n, n_inputs) in the original units."""
        torch = _torch()
        Z = torch.as_tensor(self.x_scaler.transform(np.atleast_2d(X)), dtype=torch.float64)
        with torch.no_grad():
            out = _forward(torch.as_tensor(self.theta), Z, self.spec).numpy()
        return self.y_scaler.inverse_transform(out)


@dataclasses.dataclass(frozen=True, kw_only=True)
class TrainConfig:
    """Training settings of :func:`train_mlp` (the thesis' MATLAB recipe by default), keyword-only.

    ``hidden`` hidden layer widths, e.g. ``(10,)`` (Mgherony's a1) or ``(10, 5)`` (a2); ``activation``
    ``"logsig"`` (thesis), ``"tansig"`` or ``"relu"`` for the hidden layers; ``trainer`` ``"lm"``
    (Levenberg–Marquardt, MATLAB trainlm defaults), ``"adam"`` (full batch, ``lr``) or ``"lbfgs"``;
    ``seed`` fixes the split and the initial weights; ``max_epochs``, ``max_fail`` epoch cap and
    early-stopping patience (epochs); ``fractions`` train/validation/test shares (sum 1); ``mu``,
    ``mu_dec``, ``mu_inc``, ``mu_max``, ``min_grad`` trainlm's damping schedule (dimensionless) and
    gradient stop (scaled units); ``lr`` Adam's learning rate.

    >>> TrainConfig(hidden=(10, 5)).trainer
    'lm'
    """

    hidden: Sequence[int] = (10,)
    activation: str = "logsig"
    trainer: str = "lm"
    seed: int = 0
    max_epochs: int = 1000
    max_fail: int = 6
    fractions: tuple = (0.70, 0.15, 0.15)
    mu: float = 1e-3
    mu_dec: float = 0.1
    mu_inc: float = 10.0
    mu_max: float = 1e10
    min_grad: float = 1e-7
    lr: float = 1e-2


def train_mlp(X, Y, config: TrainConfig | None = None, **fields) -> TrainedMLP:
    """Min-max scale, split 70/15/15, build ``n_in → hidden… → n_out`` and train with early stopping.

    Parameters
    ----------
    X, Y : arrays (n, n_inputs), (n, n_outputs) in original units (e.g. mm, degrees).
    config : a :class:`TrainConfig` (default: its defaults); ``fields``, its fields as keywords,
        replace those of ``config``:
    hidden : hidden layer widths, e.g. ``(10,)`` (Mgherony's a1) or ``(10, 5)`` (a2).
    activation : ``"logsig"`` (thesis), ``"tansig"`` or ``"relu"`` for the hidden layers.
    trainer : ``"lm"`` (Levenberg–Marquardt, MATLAB trainlm defaults), ``"adam"`` (full batch, ``lr``)
        or ``"lbfgs"``.
    seed : fixes the split and the initial weights.
    max_epochs, max_fail : epoch cap; stop after ``max_fail`` consecutive epochs without a new best
        validation MSE (the returned weights are the best-validation ones). For ``adam`` the epoch
        counts full-batch steps and ``max_fail`` is multiplied by 50 (a single small step rarely helps).
    mu, mu_dec, mu_inc, mu_max, min_grad : trainlm's damping schedule and gradient stop.

    Returns
    -------
    TrainedMLP; ``history`` has columns epoch, train_mse, val_mse, test_mse (scaled units), mu.
    """
    c = TrainConfig(**fields) if config is None else dataclasses.replace(config, **fields)
    hidden, activation, trainer, seed, max_epochs, max_fail = (c.hidden, c.activation, c.trainer, c.seed,
                                                               c.max_epochs, c.max_fail)
    fractions, mu, mu_dec, mu_inc, mu_max, min_grad, lr = (c.fractions, c.mu, c.mu_dec, c.mu_inc, c.mu_max,
                                                           c.min_grad, c.lr)
    torch = _torch()
    if trainer not in TRAINERS:
        raise ValueError(f"trainer must be one of {TRAINERS}, got {trainer!r}")
    X = np.asarray(X, dtype=float)
    Y = np.asarray(Y, dtype=float)
    if Y.ndim == 1:
        Y = Y[:, None]
    if X.ndim != 2 or len(X) != len(Y):
        raise ValueError(f"X must be (n, n_inputs) and Y (n, n_outputs) with the same n, got {X.shape}, {Y.shape}")
    if not (np.all(np.isfinite(X)) and np.all(np.isfinite(Y))):
        raise ValueError("X and Y must be finite")
    if max_epochs < 1 or max_fail < 1:
        raise ValueError(f"max_epochs and max_fail must be >= 1, got {max_epochs}, {max_fail}")
    spec = MLPSpec(X.shape[1], tuple(int(h) for h in hidden), Y.shape[1], activation)
    xs, ys = MinMaxScaler().fit(X), MinMaxScaler().fit(Y)
    tr, va, te = split_indices(len(X), fractions, seed)
    Zx = torch.as_tensor(xs.transform(X), dtype=torch.float64)
    Zy = torch.as_tensor(ys.transform(Y), dtype=torch.float64)
    data = {k: (Zx[idx], Zy[idx]) for k, idx in (("train", tr), ("val", va), ("test", te))}
    theta = _init_params(spec, seed)
    run = {"lm": _train_lm, "adam": _train_adam, "lbfgs": _train_lbfgs}[trainer]
    kw = dict(mu=mu, mu_dec=mu_dec, mu_inc=mu_inc, mu_max=mu_max, min_grad=min_grad) if trainer == "lm" else {}
    if trainer == "adam":
        kw, max_fail = {"lr": lr}, max_fail * 50
    theta, hist, best_epoch, reason = run(theta, spec, data, max_epochs, max_fail, **kw)
    return TrainedMLP(spec, theta.detach().numpy().copy(), xs, ys, (tr, va, te), pd.DataFrame(hist),
                      best_epoch, reason, trainer, int(seed))


def _mse(theta, spec, XY):
    X, Y = XY
    return float(((_forward(theta, X, spec) - Y) ** 2).mean())


class _EarlyStop:
    def __init__(self, theta, max_fail):
        self.best, self.best_theta, self.best_epoch, self.fails, self.max_fail = np.inf, theta.clone(), 0, 0, max_fail

    def update(self, epoch, theta, val) -> bool:
        """Record the validation MSE; True when training should stop."""
        if val < self.best:
            self.best, self.best_theta, self.best_epoch, self.fails = val, theta.clone(), epoch, 0
        else:
            self.fails += 1
        return self.fails >= self.max_fail


def _record(hist, epoch, theta, spec, data, mu=np.nan, train_mse=None):
    """Append the epoch's MSEs; ``train_mse`` may be passed when already computed at ``theta``."""
    hist.append({"epoch": epoch, "train_mse": _mse(theta, spec, data["train"]) if train_mse is None else train_mse,
                 "val_mse": _mse(theta, spec, data["val"]), "test_mse": _mse(theta, spec, data["test"]),
                 "mu": mu})
    return hist[-1]["val_mse"]


def _layers(theta, spec: MLPSpec):
    """Weight matrices and bias vectors (views into ``theta``), in :func:`_forward`'s layout."""
    Ws, bs, k = [], [], 0
    for n_in, n_out in zip(spec.sizes[:-1], spec.sizes[1:]):
        Ws.append(theta[k:k + n_in * n_out].reshape(n_out, n_in))
        k += n_in * n_out
        bs.append(theta[k:k + n_out])
        k += n_out
    return Ws, bs


def _jacobian_backprop(theta, X, spec: MLPSpec):
    """Per-sample Jacobian ``d output / d theta`` (n, n_out, P) by explicit back-propagation.

    The same products autograd forms for ``vmap(jacrev(_forward))`` (sigmoid' = (g·(1−y))·y,
    ``tanh_backward``, relu mask), batched over samples and outputs in one pass, without autograd's
    per-call overhead (~10-50x faster for these tiny nets).
    """
    torch = _torch()
    Ws, bs = _layers(theta, spec)
    act = {"logsig": torch.sigmoid, "tansig": torch.tanh, "relu": torch.relu}[spec.activation]
    hs, h = [X], X
    for li in range(len(Ws)):
        h = h @ Ws[li].T + bs[li]
        if li < len(Ws) - 1:
            h = act(h)
        hs.append(h)
    n, no = X.shape[0], spec.sizes[-1]
    g = torch.eye(no, dtype=X.dtype)[:, None, :].expand(no, n, no)   # (output, sample, width)
    blocks = [None] * len(Ws)
    for li in range(len(Ws) - 1, -1, -1):
        gW = g[:, :, :, None] * hs[li][None, :, None, :]
        blocks[li] = (gW.reshape(no, n, -1), g)
        if li > 0:
            gh = (g.reshape(no * n, -1) @ Ws[li]).reshape(no, n, -1)
            y = hs[li][None]
            if spec.activation == "logsig":
                g = gh * (1 - y) * y
            elif spec.activation == "tansig":
                g = torch.ops.aten.tanh_backward(gh, y)
            else:
                g = gh * (y > 0)
    return torch.cat([t for b in blocks for t in b], dim=2).permute(1, 0, 2)


def _lm_jacobian(theta, X, spec: MLPSpec):
    """A function ``theta -> J`` (n·n_out, P) for LM: the explicit back-propagation when it equals
    autograd's ``vmap(jacrev)`` bit for bit at the initial ``theta`` (the same floating-point
    operations in the same order: true for the thesis's nets a1 and a2), otherwise autograd, so a
    trained network never depends on which one is used."""
    torch = _torch()
    from torch.func import jacrev, vmap

    auto = vmap(jacrev(lambda th, x: _forward(th, x, spec)), in_dims=(None, 0))
    n_res = X.shape[0] * spec.sizes[-1]
    J_auto = auto(theta, X)
    if torch.equal(J_auto, _jacobian_backprop(theta, X, spec)):
        return lambda th: _jacobian_backprop(th, X, spec).reshape(n_res, -1)
    return lambda th: auto(th, X).reshape(n_res, -1)


def _train_lm(theta, spec, data, max_epochs, max_fail, mu, mu_dec, mu_inc, mu_max, min_grad):
    torch = _torch()

    X, Y = data["train"]
    n_res = Y.numel()
    jac = _lm_jacobian(theta, X, spec)
    eye = torch.eye(theta.numel(), dtype=torch.float64)
    hist = []
    stop = _EarlyStop(theta, max_fail)
    stop.update(0, theta, _record(hist, 0, theta, spec, data, mu))
    reason = "max_epochs"
    with torch.no_grad():
        out = _forward(theta, X, spec)
    for epoch in range(1, max_epochs + 1):
        e = (Y - out).reshape(-1)       # the output at theta: computed when theta was accepted
        J = jac(theta)                                # d output / d theta, (n*n_out, P)
        JtJ, Jte = J.T @ J, J.T @ e
        perf = float(e @ e) / n_res
        if float(2 * Jte.abs().max()) / n_res < min_grad:
            reason = "min_grad"
            break
        while True:
            step = torch.linalg.solve(JtJ + mu * eye, Jte)
            new = theta + step
            with torch.no_grad():
                out_new = _forward(new, X, spec)
            perf_new = float(((Y - out_new) ** 2).mean())
            if perf_new < perf:
                theta, mu, out = new, mu * mu_dec, out_new
                break
            mu *= mu_inc
            if mu > mu_max:
                break
        if mu > mu_max:
            reason = "mu_max"
            break
        # train MSE at the accepted theta = perf_new ((Y - f)^2 and (f - Y)^2 are the same floats)
        if stop.update(epoch, theta, _record(hist, epoch, theta, spec, data, mu, train_mse=perf_new)):
            reason = "validation_stop"
            break
    return stop.best_theta, hist, stop.best_epoch, reason


def _train_adam(theta, spec, data, max_epochs, max_fail, lr):
    torch = _torch()
    X, Y = data["train"]
    th = theta.clone().requires_grad_(True)
    opt = torch.optim.Adam([th], lr=lr)
    hist = []
    stop = _EarlyStop(theta, max_fail)
    stop.update(0, theta, _record(hist, 0, theta.detach(), spec, data))
    reason = "max_epochs"
    for epoch in range(1, max_epochs + 1):
        opt.zero_grad()
        loss = ((_forward(th, X, spec) - Y) ** 2).mean()
        loss.backward()
        opt.step()
        cur = th.detach()
        if stop.update(epoch, cur, _record(hist, epoch, cur, spec, data)):
            reason = "validation_stop"
            break
    return stop.best_theta, hist, stop.best_epoch, reason


def _train_lbfgs(theta, spec, data, max_epochs, max_fail):
    torch = _torch()
    X, Y = data["train"]
    th = theta.clone().requires_grad_(True)
    opt = torch.optim.LBFGS([th], lr=1.0, max_iter=20, history_size=50, line_search_fn="strong_wolfe")

    def closure():
        opt.zero_grad()
        loss = ((_forward(th, X, spec) - Y) ** 2).mean()
        loss.backward()
        return loss

    hist = []
    stop = _EarlyStop(theta, max_fail)
    stop.update(0, theta, _record(hist, 0, theta.detach(), spec, data))
    reason = "max_epochs"
    for epoch in range(1, max_epochs + 1):
        opt.step(closure)
        cur = th.detach()
        if stop.update(epoch, cur, _record(hist, epoch, cur, spec, data)):
            reason = "validation_stop"
            break
    return stop.best_theta, hist, stop.best_epoch, reason
