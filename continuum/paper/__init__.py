"""Presentation of the continuum side: the paper's figures, the continuum report and the stability maps.
Numerics live one level up (continuum/); nothing here is imported by them."""
