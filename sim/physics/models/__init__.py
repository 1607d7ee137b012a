"""Models built by driving the physics world: its tabular transition model, the
stochastic model at a fidelity (V*: build, solve, rollouts), policy rollouts, the continuous
optimum, and their disk cache.
"""
