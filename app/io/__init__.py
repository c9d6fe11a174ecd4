"""Files: images in and out (images.py), tone curves, denoising, the check made before reading a
file the user names, and the entries of pathtrace's caches on disk."""
