"""One sub-package per reproduced work; each gathers that work's claim recipes.

A *recipe* is a zero-argument function (usually cached) that computes one printed number, or a
mapping of related numbers, from the algorithms in :mod:`cnclab`'s pipeline modules. The claims
ledger (``data/claims.csv``) names recipes in its ``computed_by`` column.
"""
from __future__ import annotations

WORKS = {
    "jacso2021": {
        "seed_file": "000_690a1ed8f09fd780.txt",
        "citation": ("Jacsó, Á. (2021). *Tool path generation for pocket machining with uniform tool "
                     "load.* PhD dissertation booklet, Budapest University of Technology and Economics, "
                     "Department of Manufacturing Science and Engineering. Supervisor: T. Szalay."),
    },
    "kim_yang2006": {
        "seed_file": "002_d412f01ccb8e936f.txt",
        "citation": ("Kim, H.-C. & Yang, M.-Y. (2006). An optimum 2.5D contour parallel tool path. "
                     "*International Journal of Precision Engineering and Manufacturing* (KSPE), 7(3). "
                     "KAIST; manuscript received 25 March 2006, accepted 4 April 2006."),
    },
    "hoang2024": {
        "seed_file": "003_216a87306e3bb9cf.txt",
        "citation": ("Hoang, V.-Q. (2024). Toolpath generation on 3-axes milling using constant volume "
                     "method. *Journal of Mechanical Engineering – Problems of Machinery*, 27(2), 60ff. "
                     "https://doi.org/10.15407/pmach2024.02.060"),
    },
    "mgherony2024": {
        "seed_file": "004_6087ee43271ee0e7.txt",
        "citation": ("Mgherony, A. W. (2024). *Optimization of ball end milling tool path in case of free "
                     "form milling.* PhD dissertation, Óbuda University, Doctoral School of Materials "
                     "Sciences and Technologies, Budapest. Supervisor: B. Mikó."),
    },
}
