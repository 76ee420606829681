"""``granstokes study``: a grid of DEM drives (pressures x drives x seeds) of one material, sized from an
independent calibration, run on the project's executor (Dask), compared with every model in one report."""
