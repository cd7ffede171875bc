"""Runs grainflow on a case with `--set` overrides and reads its summary:
shared by the sweep scripts of this folder."""
import json
import os
import subprocess


def run_case(binary, case, out, sets, resume=False, threads=None):
    """`binary run case --out out --set s ...`. Returns the parsed
    summary.json and None, or None and the last line grainflow wrote to
    stderr when the case was refused (nothing written). With `resume`, a
    run stopped before its end (a session or a job limit) goes on from
    its newest checkpoint in `out` (`--restart auto`; the case needs a
    `[checkpoint]` section). `threads`: `--threads`, when given."""
    command = [binary, "run", case, "--out", out]
    if threads is not None:
        command += ["--threads", str(threads)]
    if resume:
        command += ["--restart", "auto"]
    for s in sets:
        command += ["--set", s]
    finished = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    summary_path = os.path.join(out, "summary.json")
    if not os.path.exists(summary_path):
        lines = finished.stderr.strip().splitlines()
        return None, lines[-1] if lines else "failed"
    with open(summary_path) as f:
        return json.load(f), None


def finished_summary(out):
    """The summary.json of a run in `out` that ended (at its end time, at
    rest, refused mid-run or unstable), or None: no run there yet, or one
    stopped by a signal or a wall-clock limit, which `run_case` with
    `resume` takes on from its newest checkpoint."""
    path = os.path.join(out, "summary.json")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        summary = json.load(f)
    return None if summary.get("status") == "stopped" else summary
