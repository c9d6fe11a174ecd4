"""`pathtrace bench`: the report's measurement (report.py), the scenes that are files
(scenes.py), first-image and load timings, Mitsuba 3 timed beside pathtrace, and the trace
split and traversal counts. The renderer imports nothing from this package."""
