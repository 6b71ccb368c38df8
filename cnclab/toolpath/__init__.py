"""Tool paths: generators (zig-zag, offsets, constant engagement, trochoids) and file formats (APT, G-code)."""
