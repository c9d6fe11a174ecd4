"""The command line: main.py parses it and runs one command, each command group a module with its
parser (render, view, bench, farm, convert, listing); console.py is the entry point around it,
interrupts.py the signal handling. This file imports nothing, so that the entry point puts its
signal handlers in place before the package's imports (NumPy, PyOpenCL) begin."""
