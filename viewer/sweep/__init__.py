"""`hmblur sweep`: many comparisons (scenes x times x shutters x sizes x variants) on Dask."""
