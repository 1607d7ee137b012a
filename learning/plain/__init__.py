"""Your own learner in plain Python: the protocol and its checks, its training loop on a
tabular model, and any fixed policy as a state the compiled readers grade.
"""
