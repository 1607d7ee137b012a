"""The fast path: the motion primitive for many robots in compiled code, the geometry
queries it makes, its named state, and the batch of N robots in one Space that drives it.
"""
