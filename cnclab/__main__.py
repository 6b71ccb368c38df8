"""Command line: ``python -m cnclab <command> ...``.

Commands are imported lazily, so ``python -m cnclab claims`` does not import torch.
"""
from __future__ import annotations

import importlib
import sys

#: command -> (module, one-line help). Each module has ``main(argv) -> int``.
COMMANDS = {
    "claims": ("cnclab.claims", "compute every ledger row; --work W, --json, --report DIR"),
    "reproduce": ("cnclab.reproduce", "execute every notebook, export HTML/figures, write the claims report"),
    "finish-path": ("cnclab.nc.cli_finish_path", "drop-cutter zig-zag finishing path (APT) over an STL part, the input of spindle"),
    "spindle": ("cnclab.nc.cli_spindle", "constant-v_c spindle/feed post-processing of an APT file against an STL"),
    "nb": ("cnclab.notebook_tools", "notebook housekeeping: from-py, strip, list"),
    "site": ("cnclab.site", "build the offline site build/site/index.html from what build/ holds"),
    "analyze": ("cnclab.nc.cli_analyze", "score any G-code program on a pocket job (summary, traces, engagement map)"),
    "plan": ("cnclab.nc.cli_plan", "plan a pocket job and write a machine-safe program"),
    "job": ("cnclab.toolpath.job_format", "the job file format: reference (--schema), JSON schema, check a file"),
    "job-from-drawing": ("cnclab.nc.cli_drawing", "write a pocket job from a DXF/SVG drawing and cutting data"),
    "programs": ("cnclab.works.programs", "write every program the collection produces to build/gcode/<work>/"),
    "warm": ("cnclab.warm", "compile the shared numba kernels once into their cache (make test/reproduce run it first)"),
}


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help") or argv[0] not in COMMANDS:
        print("usage: python -m cnclab <command> [options]\n\ncommands:")
        for name, (_, hlp) in COMMANDS.items():
            print(f"  {name:<12} {hlp}")
        if argv and argv[0] not in ("-h", "--help"):
            print(f"\nerror: unknown command {argv[0]!r}")
            return 2
        return 0
    mod = importlib.import_module(COMMANDS[argv[0]][0])
    return int(mod.main(argv[1:]) or 0)


if __name__ == "__main__":
    sys.exit(main())
