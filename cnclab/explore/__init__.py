"""Interactive explorers (ipywidgets) and offline 3D views (plotly) for teaching and reading.

* :mod:`cnclab.explore.scenes` — pure functions computing what each explorer draws (unit-tested);
* :mod:`cnclab.explore.draw` — their matplotlib drawings;
* :mod:`cnclab.explore.widgets` — the explorers: ``thesis1_explorer()``, ``ce_growth_explorer()``,
  ``trochoid_explorer()``, ``kim_yang_explorer()``, ``hoang_explorer()``,
  ``working_diameter_explorer()``, ``cusp_explorer()``, ``spindle_explorer()``;
* :mod:`cnclab.explore.views3d` — plotly 3D views that render in JupyterLab and in offline HTML.

This is the top layer of the package: it may import every other layer, nothing imports it.
"""
