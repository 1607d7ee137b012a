"""The references a route learner is judged against (docs/methods.md, "The references"):
the classic ways of learning a route in a map that is not known.

* :mod:`.lrta_star`: learning by trials (Korf 1990), a heuristic raised along the routes
  tried;
* :mod:`.fsa_replan`: planning on the optimistic map (the free-space assumption of D*
  Lite, Koenig & Likhachev 2002), replanned after every move;
* :mod:`.r_max`: model-based RL with optimism (Brafman & Tennenholtz 2002), an untried
  move valued by the free-space distance (Asmuth, Littman & Zinkov 2008);
* :mod:`.mf_r_max`: R-max over levels of fidelity (Cutler, Walsh & How 2015), the grid's
  values and known moves carried to a physics rung, trusted until contradicted;
* :mod:`.abstraction_shaping`: Q-learning shaped by the value of a coarser abstraction of
  the map (after Cipollone et al. 2023), the modern form of SARSA-RS's coarse-grid Φ.

Each reads bumps the one way every model learner here reads them
(:mod:`learning.parts.move_reading`), so it runs in the grid and in the physics world at
every fidelity.
"""
