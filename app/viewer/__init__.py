"""The interactive viewer: a GLFW window (window.py), the image's way to it (display.py, drawn by
a moderngl shader), fly controls and an imgui panel. Nothing in the core imports this package:
only api.view(), the `view` command and `bench --display` do."""
