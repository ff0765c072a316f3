"""A wrapper around the real ngspice that damages what it returns (fault-injection tests).

``install(bindir, mode, say="")`` writes ``bindir/ngspice``: ``ngspice -v`` is answered by the
real ngspice (so results would be filed under the real version's store keys), any other call
runs the real ngspice with the same arguments and then, when it succeeded, rewrites its raw
file (``-b -r RAW DECK``) according to ``mode`` and prints ``say`` on stdout:

* ``"thin"``: every 25th point kept (and the last one, so that the run still reaches t_stop);
* ``"huge"``: every value but time set to 1e300;
* ``"squeeze"``: time halved, except the last point;
* ``"rename"``: every vector but time renamed (``v(o0)`` -> ``v(q_o0)``);
* ``"nan"``: every value but time NaN;
* ``"none"``: the raw file left as it is (only ``say`` is added).

Run as a script (``python wrapped_ngspice.py MODE RAW``) it does the rewriting.
"""
from __future__ import annotations

import os
import shlex
import shutil
import stat
import sys
from pathlib import Path

import numpy as np

MODES = ("thin", "huge", "squeeze", "rename", "nan", "none")


def install(bindir: Path, mode: str, say: str = "") -> Path:
    if mode not in MODES:
        raise ValueError(mode)
    real = shutil.which("ngspice")
    assert real is not None and not real.startswith(str(bindir))
    bindir.mkdir(parents=True, exist_ok=True)
    exe = bindir / "ngspice"
    exe.write_text("#!/bin/sh\n"
                   f'if [ "$1" = "-v" ]; then exec "{real}" -v; fi\n'
                   f'"{real}" "$@" || exit $?\n'
                   f'"{sys.executable}" "{Path(__file__).resolve()}" {mode} "$3" || exit 3\n'
                   + (f"printf '%s\\n' {shlex.quote(say)}\n" if say else "")
                   + "exit 0\n")
    exe.chmod(exe.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
    return exe


def _read(path: Path):
    data = path.read_bytes()
    head, _, body = data.partition(b"Binary:\n")
    lines = head.decode().splitlines()
    nvar = int(next(ln for ln in lines if ln.startswith("No. Variables:")).split(":")[1])
    start = lines.index("Variables:") + 1
    var_lines = lines[start:start + nvar]
    pre = lines[:start]
    values = np.frombuffer(body, dtype="<f8")
    values = values[:values.size // nvar * nvar].reshape(-1, nvar).copy()
    return pre, var_lines, values


def _write(path: Path, pre, var_lines, values) -> None:
    pre = [f"No. Points: {values.shape[0]}" if ln.startswith("No. Points:") else ln
           for ln in pre]
    head = "\n".join(pre + var_lines) + "\nBinary:\n"
    path.write_bytes(head.encode() + np.ascontiguousarray(values, dtype="<f8").tobytes())


def damage(mode: str, raw: Path) -> None:
    pre, var_lines, values = _read(raw)
    if mode == "thin":
        keep = np.unique(np.r_[np.arange(0, values.shape[0], 25), values.shape[0] - 1])
        values = values[keep]
    elif mode == "huge":
        values[:, 1:] = 1e300
    elif mode == "nan":
        values[:, 1:] = np.nan
    elif mode == "squeeze":
        values[:-1, 0] *= 0.5
    elif mode == "rename":
        out = [var_lines[0]]
        for ln in var_lines[1:]:
            idx, name, kind = ln.split()
            inner = name[name.index("(") + 1:-1] if "(" in name else name
            out.append(f"\t{idx}\tv(q_{inner})\t{kind}")
        var_lines = out
    _write(raw, pre, var_lines, values)


if __name__ == "__main__":
    damage(sys.argv[1], Path(os.getcwd()) / sys.argv[2])
