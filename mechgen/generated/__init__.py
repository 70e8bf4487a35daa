"""Committed generated kernels of the shipped scenes (written by `mechgen regen`; data, not modules).

mechgen.pipeline.read_committed loads `<model>/<key>.c` with its `.c.json`; mechgen.scene.info reads
`<model>/info.json`.
"""
