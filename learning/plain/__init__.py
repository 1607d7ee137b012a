"""Your own learner in plain Python: the protocol and its checks (:mod:`~learning.plain.learner`,
with the batch of such learners the physics loop drives), and any fixed policy as a state
the compiled readers grade (:mod:`~learning.plain.policy`). Its grid loop is a driver:
:mod:`learning.drivers.plain_train`.
"""
