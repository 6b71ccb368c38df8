"""Geometry: surfaces, contours and tool-surface contact (lengths in mm, angles as documented per function)."""
