"""Linear analyses about an operating point and rotor post-processing: undamped modes (``modes``),
stability of x' = A x (``stability``), damped complex modes (``damped``) and Campbell diagrams with
critical speeds (``campbell``)."""
