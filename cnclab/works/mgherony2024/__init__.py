"""Mgherony (2024), PhD dissertation, Óbuda University: one recipe module per chapter group."""
