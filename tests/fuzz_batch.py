"""Runs a batch of fuzz cases in one process (run_batch starts it with a time limit, for
tests/test_fuzz_inputs.py, test_fuzz_scenes.py and test_fuzz_files.py), so that the device is
opened and the generic kernels built once for all of them, where a process per case spent about a
second of CPU on its start: `python -m tests.fuzz_batch cases.json results.json`.

A case is {"cwd": folder, and "argv": a command line for pathtrace.cli.main.main, or "code": Python
run with `pathtrace`, `np` and `UserError` in scope}. Its result: {"status": the command's exit
status (a code case: 0 where it ran through, 1 where it raised pathtrace.UserError, None where it
raised anything else), "stderr": what it printed to standard error (Python's warnings, NumPy's
among them, included: tests/commands.py, as_a_command), "error": a code case's UserError message,
"traceback": where anything else escaped}."""

import json
import os
import subprocess
import sys
import traceback
from pathlib import Path

from tests.commands import ROOT, as_a_command

BATCH_SECONDS = 240         # a batch's time limit: the generic kernels' build, then cases of 8x6 pixels


def run_batch(cases: list, folder: Path) -> list:
    """Each case's result, the batch run in a process of its own (a hang, a crash or a signal
    takes that process, not the test's: the cases before it keep their results, and the test
    names the case that had none). What reached the standard error's file descriptor rather
    than Python's sys.stderr, which each case's capture holds (a driver's or a library's own
    line, OpenCV's among them), fails the batch: the bar is no line from below."""
    path, out = folder / "cases.json", folder / "results.json"
    path.write_text(json.dumps(cases))
    env = {**os.environ, "PATHTRACE_PROGRAM": "generic"}
    below = ""
    try:
        below = subprocess.run([sys.executable, "-m", "tests.fuzz_batch", str(path), str(out)], cwd=ROOT, env=env,
                               timeout=BATCH_SECONDS, capture_output=True, text=True).stderr
    except subprocess.TimeoutExpired:
        pass
    results = json.loads(out.read_text()) if out.exists() else []
    assert len(results) == len(cases), f"no result for case {len(results)} within {BATCH_SECONDS} s: " \
        + json.dumps(cases[len(results)])[:2000]
    assert not below.strip(), f"written below Python's capture by the batch:\n{below[:2000]}\n" + json.dumps(cases)[:3000]
    return results


def run_case(case: dict) -> dict:
    import numpy as np

    import pathtrace
    from pathtrace.cli.main import main
    from pathtrace.errors import UserError

    result = {"status": None, "stderr": "", "error": "", "traceback": ""}
    with as_a_command(case["cwd"], keep_devices=True) as (_, err):
        try:
            if "argv" in case:
                result["status"] = main(case["argv"])
            else:
                exec(case["code"], {"pathtrace": pathtrace, "np": np, "UserError": UserError})
                result["status"] = 0
        except UserError as e:
            result["status"], result["error"] = 1, str(e)
        except SystemExit as e:
            result["status"] = e.code
        except BaseException:
            result["traceback"] = traceback.format_exc()
    result["stderr"] = err.getvalue()
    return result


def main():
    cases = json.loads(open(sys.argv[1]).read())
    results = []
    for case in cases:
        results.append(run_case(case))
        with open(sys.argv[2], "w") as f:      # each case's result kept as it ends: a hang shows where
            json.dump(results, f)


if __name__ == "__main__":
    main()
