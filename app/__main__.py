from pathtrace.cli.console import run

run()
