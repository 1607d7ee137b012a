"""The compiled plumbing: the one door onto every method's hooks, the fused kernels,
named states, the generator handle, numba's disk cache.
"""
