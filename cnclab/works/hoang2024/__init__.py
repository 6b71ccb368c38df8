"""Hoang (2024): constant-volume ball-end zig-zag — recipes in :mod:`.constant_volume`."""
