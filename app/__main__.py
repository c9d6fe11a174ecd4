from app.console import run

run()
