"""Committed generated kernels of the shipped scenes (written by `mechgen regen`; data, not modules, but for
`liegroup/`).

mechgen.pipeline.read_committed loads `<model>/<key>.c` with its `.c.json`; mechgen.scene.info reads
`<model>/info.json`. `liegroup/` holds modules: the runtime's numeric so(3)/se(3) maps generated from
mechgen/symbolic/liegroup.py (numpy_maps.py, casadi_maps.py, imported by mechgen.runtime.rods; liegroup_maps.h,
included by runtime/csrc/rod_elements.c).
"""
