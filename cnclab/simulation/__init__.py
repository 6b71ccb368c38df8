"""Material-removal simulation: dixel and pixel models (2.5D), height fields (3-axis ball end)."""
