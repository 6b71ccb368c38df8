"""Cutting physics: cutting speed, spindle speed, feed, MRR, chip thickness, surface-profile roughness."""
