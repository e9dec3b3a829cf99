"""What every study runs on: the sweep of a scene's variations and the pool that runs them (local processes or a
Dask cluster, the run store), the one threshold search, and the one way a report is put in words."""
