"""Studies of the fidelity ladder: continuous vs gridded, predictivity, the
grading check, aliasing.
"""
