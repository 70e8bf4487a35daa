"""A rod's end conditions, in a module of their own so that the analyses' scene schemas read them without
loading the rod solvers (and scipy.sparse) when a scene has no rod."""

#: the end conditions of a rod's ends
ENDS = ("clamped", "pinned", "free")
#: the pairs (base, tip) that leave a rigid motion free: refused for statics
UNCONSTRAINED = {("free", "free"), ("pinned", "free"), ("free", "pinned")}
