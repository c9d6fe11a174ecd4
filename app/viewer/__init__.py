"""The interactive viewer: a GLFW window, a moderngl display of the accumulation buffer, fly
controls and an imgui panel. Nothing in the core imports this package."""
