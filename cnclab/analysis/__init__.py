"""Analysis and models: designed experiments, regression (statsmodels), neural networks (torch, lazy)."""
