"""NC layer: APT CL files, RS274/NGC G-code (write, read, program time), the spindle-speed
post-processor and program output of planned tool paths.

Dependency order (enforced by ``tests/test_layers.py``): geometry -> simulation / cutting -> toolpath
-> nc -> works. Nothing below ``nc`` imports it.
"""
