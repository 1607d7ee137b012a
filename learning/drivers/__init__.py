"""What runs a learner: the fused training loop on a tabular model and its plain-Python
mirror, the step-by-step and batch agents, a fresh state of any method, checkpoints.
"""
