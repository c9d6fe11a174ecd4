from pathtrace.console import run

run()
