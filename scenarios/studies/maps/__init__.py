"""Studies on maps of many kinds: the map suite, the RNH-QL+ ablation, held-out
maps, large maps, the greedy test from S.
"""
