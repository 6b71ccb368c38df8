"""Kim & Yang (2006): constant-MRR contour-parallel path — recipes in :mod:`.constant_mrr_pocket`."""
