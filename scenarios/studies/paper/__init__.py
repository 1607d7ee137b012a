"""Studies of the paper's claims: reproduce_paper, reward design, the oracle bound,
the scaling of the paper's arenas.
"""
