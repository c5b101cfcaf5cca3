"""The run archive: what it holds and how it is written, apart from the pictures that read it.

  schema          every variable of a run archive, declared once: dimensions, CF unit, long name
  run_variables   STE, DTE, their spectra and named peaks, mesh efficiency, tooth springs; the title
  mesh            mesh stiffness (with ISO 6336-1 beside it), static and dynamic tooth forces
  modes           modes, damping ratios, free decay, critical speeds
  lightening      mass, inertia and root stress per gear
  order_tracking  the run-up's order map
  spectra         amplitude spectra and named peaks (numpy only)
  summary         the summary scalars of a run archive (what a study archives per point)
  netcdf          CF NetCDF writes, provenance, code fingerprint: imports nothing of `study`,
                  so every part of it (run, sweep, inputs, verify, report) can write files

A study's archive over its grid is `study.sweep.archive`; the pictures are `study.report`.
"""
