"""Runs a batch of fuzz cases in one process (tests/test_fuzz_inputs.py starts it with a time
limit), so that the device is opened and the generic kernels built once for all of them:
`python -m tests.fuzz_batch cases.json results.json`.

A case is {"cwd": folder, and "argv": a command line for pathtrace.cli.main.main, or "code": Python
run with `pathtrace`, `np` and `UserError` in scope}. Its result: {"status": the command's exit
status (a code case: 0 where it ran through, 1 where it raised pathtrace.UserError, None where it
raised anything else), "stderr": what it printed to standard error (Python's warnings, NumPy's
among them, included: tests/commands.py, as_a_command), "error": a code case's UserError message,
"traceback": where anything else escaped}."""

import json
import sys
import traceback

from tests.commands import as_a_command


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
