"""3D views (plotly) of the Mgherony ch. 7-9 part, its CL paths and the reordered path — offline.

Rendered in JupyterLab by plotly's own JupyterLab extension (``jupyterlab-plotly``, shipped inside the
``plotly`` wheel: no network) and, in exported or static HTML, by plotly.js **inlined** into the page
(``include_plotlyjs=True``; never the CDN). :func:`show` returns an object carrying both
representations; :func:`save_html` writes a standalone page next to the figures
(``build/figures/<work>/<name>.html``). Lengths in mm.

>>> import numpy as np
>>> from cnclab.geometry.mesh import TriMesh
>>> m = TriMesh.from_triangles(np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0], [0, 1, 0]]], float))
>>> V, F = mesh_arrays(m)
>>> len(V), F.tolist()
(4, [[0, 1, 2], [1, 3, 2]])
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import plotly.graph_objects as go
import plotly.io as pio

from ..fileio import atomic_write
from ..paths import figures_dir

__all__ = ["mesh_arrays", "part_figure", "path_figure", "reorder_figure", "offline_html", "show", "save_html",
           "View", "reset_plotlyjs"]

_state = {"plotlyjs_sent": False}


def mesh_arrays(mesh, decimals: int = 9):
    """Shared vertices (V, 3) mm and faces (F, 3) indices of a triangle soup (corners merged when equal
    to ``decimals`` decimals), in first-seen order; ``V[F]`` reproduces ``mesh.triangles``."""
    corners = np.asarray(mesh.triangles, float).reshape(-1, 3)
    key = np.round(corners, decimals)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)                   # unique rows in first-seen order
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return corners[first[order]], rank[inverse.ravel()].reshape(-1, 3)


def _mesh_trace(mesh, name="part (STL)"):
    V, F = mesh_arrays(mesh)
    return go.Mesh3d(x=V[:, 0], y=V[:, 1], z=V[:, 2], i=F[:, 0], j=F[:, 1], k=F[:, 2], color="lightgray",
                     opacity=1.0, flatshading=True, name=name, showlegend=True,
                     lighting={"ambient": 0.5, "diffuse": 0.7}, hoverinfo="skip")


def _layout(fig, title):
    fig.update_layout(title=title, height=560, margin={"l": 0, "r": 0, "t": 40, "b": 0},
                      scene={"aspectmode": "data", "xaxis_title": "x [mm]", "yaxis_title": "y [mm]",
                             "zaxis_title": "z [mm]"}, legend={"x": 0, "y": 1})
    return fig


def part_figure(mesh, title="Chapter 8 test part (STL)"):
    """The STL part as a shaded mesh."""
    return _layout(go.Figure([_mesh_trace(mesh)]), title)


def path_figure(mesh, xyz, values, label, unit, title="", lift_mm=0.0, max_points=20000):
    """Mesh + CL path ``xyz`` (N, 3) mm as points coloured by ``values`` (N,) with a colour bar
    ``"label [unit]"``; ``lift_mm`` raises the path above the surface for visibility."""
    xyz = np.asarray(xyz, float)
    values = np.asarray(values, float)
    if xyz.ndim != 2 or xyz.shape[1] != 3 or len(values) != len(xyz):
        raise ValueError(f"xyz must be (N, 3) and values (N,), got {xyz.shape} and {values.shape}")
    step = max(1, int(np.ceil(len(xyz) / max_points)))
    P, v = xyz[::step], values[::step]
    path = go.Scatter3d(x=P[:, 0], y=P[:, 1], z=P[:, 2] + lift_mm, mode="lines+markers", name=f"CL path: {label}",
                        line={"color": "rgba(60,60,60,0.35)", "width": 1},
                        marker={"size": 2.2, "color": v, "colorscale": "Viridis",
                                "colorbar": {"title": {"text": f"{label} [{unit}]"}}},
                        hovertemplate=f"x %{{x:.2f}} y %{{y:.2f}} z %{{z:.2f}} mm<br>{label} %{{marker.color:.4g}} {unit}"
                                      "<extra></extra>")
    return _layout(go.Figure([_mesh_trace(mesh), path]), title)


def reorder_figure(mesh, points, order, jump, title="Reordered path", lift_mm=0.3):
    """Mesh + the path visiting ``points[order]`` (mm); feed moves blue, jumps (``jump[i]``: the move
    into the i-th visited point) dashed red."""
    Q = np.asarray(points, float)[np.asarray(order)]
    jump = np.asarray(jump, bool)
    feed = Q.copy()
    feed[jump] = np.nan                               # break the line at each jump
    seg = [np.vstack([Q[i - 1], Q[i], [np.nan] * 3]) for i in np.flatnonzero(jump) if i > 0]
    J = np.vstack(seg) if seg else np.empty((0, 3))
    traces = [_mesh_trace(mesh),
              go.Scatter3d(x=feed[:, 0], y=feed[:, 1], z=feed[:, 2] + lift_mm, mode="lines", name="feed moves",
                           line={"color": "royalblue", "width": 3}),
              go.Scatter3d(x=J[:, 0], y=J[:, 1], z=J[:, 2] + lift_mm, mode="lines", name=f"jumps ({len(seg)})",
                           line={"color": "crimson", "width": 4, "dash": "dash"})]
    return _layout(go.Figure(traces), title)


def offline_html(fig, include_plotlyjs: bool = True, full_html: bool = False) -> str:
    """HTML of ``fig`` with plotly.js inlined (``include_plotlyjs=True``) or assumed already loaded."""
    return pio.to_html(fig, include_plotlyjs=bool(include_plotlyjs), full_html=full_html,
                       config={"displaylogo": False, "responsive": True})


def reset_plotlyjs() -> None:
    """Forget that plotly.js was sent (the next :func:`show` inlines it again, e.g. in a new page)."""
    _state["plotlyjs_sent"] = False


class View:
    """Display wrapper: plotly's MIME bundle for JupyterLab + offline HTML (plotly.js inlined the first
    time in a kernel) for notebook exports."""

    def __init__(self, fig):
        self.fig = fig

    def _repr_mimebundle_(self, **kwargs):
        first = not _state["plotlyjs_sent"]
        _state["plotlyjs_sent"] = True
        return {"application/vnd.plotly.v1+json": json.loads(pio.to_json(self.fig, validate=False)),
                "text/html": offline_html(self.fig, include_plotlyjs=first),
                "text/plain": f"<3D view: {self.fig.layout.title.text}>"}


def show(fig) -> View:
    """Return a displayable :class:`View` of ``fig`` (last expression of a notebook cell)."""
    return View(fig)


def save_html(fig, name: str, work: str) -> Path:
    """Write ``build/figures/<work>/<name>.html``: a standalone page with plotly.js inlined (offline)."""
    path = figures_dir(work) / f"{name}.html"
    atomic_write(path, offline_html(fig, include_plotlyjs=True, full_html=True))
    return path
