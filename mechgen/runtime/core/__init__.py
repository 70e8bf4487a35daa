"""The core of the runtime: loading generated kernels (``kernels``), the compiled lumped and lattice
system (``system``) and its typed metadata (``meta``), the options objects' base (``options``),
sparsity patterns (``pattern``), time integration (``integrate``) and parallel parameter sweeps
(``sweep``)."""
