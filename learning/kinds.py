"""Slot layout of the agent state: rule-family ids and indices into the packed vectors.

numba's on-disk cache cannot key on functions passed as arguments, so one
compiled kernel serves every method and switches on the rule family (``kind``).
The agent state (:class:`learning.state.AgentState`) is therefore a fixed
tuple of arrays; these constants name what each slot means.
"""

# ---- rule families (AgentState.ivar[I_KIND])
QL = 0  # Q-learning (st-ql, q-opt)
RNQL = 1  # Q from sigmoid nets, Watkins Q(lambda) gradient traces
PFH = 2  # Q-learning + static potential shaping
SARSARS = 3  # SARSA + abstract-V shaping
HAQL = 4  # heuristically accelerated Q-learning
RNHQL = 5  # Q-table + RBF V_NN dynamic shaping
QLAMBDA = 6  # tabular Watkins Q(lambda)
DYNA = 7  # Dyna-Q
RNHQLP = 8  # RNH-QL+: map-sized sparse RBF V_NN, shaped planning (learning.rules_plus)

# ---- params: float64[N_PARAMS]
P_EPS, P_ALPHA, P_GAMMA, P_LAMBDA = 0, 1, 2, 3
P_X0 = 4  # first method-specific slot; meaning per family:
P_Q0 = 4  # QL: initial Q
P_TRACE_MIN = 4  # QLAMBDA: drop traces below this
P_QSCALE = 4  # RNQL: Q = q_scale * net
P_OMEGA, P_ALPHA_V = 4, 5  # SARSARS
P_XI, P_BETA_H, P_ETA, P_EXPLORED = 4, 5, 6, 7  # HAQL
P_NPLAN = 4  # DYNA
P_BETA, P_WARMUP, P_FREEZE = 4, 5, 6  # RNHQL (P_FREEZE = inf: never)
N_PARAMS = 8
# RNHQLP packs a longer vector (N_PARAMS_PLUS); slots from P_X0 on:
PP_BETA, PP_WARMUP, PP_FREEZE, PP_NPLAN = 4, 5, 6, 7
PP_VTARGET, PP_SCALE, PP_LAMQ, PP_TRACE_MIN = 8, 9, 10, 11
PP_NORMALISE, PP_LEAKFREE, PP_REBASE = 12, 13, 14
PP_LOOKAHEAD, PP_NFIT = 15, 16
N_PARAMS_PLUS = 17

# ---- ivar: int64[N_IVAR], scalar integer state
I_KIND = 0  # rule family
I_EPISODE = 1  # episodes completed = 0-based index of the running episode
I_PENDING = 2  # SARSA: next action already drawn at s' (-1: none)
I_NTRACE = 3  # QLAMBDA: length of the touched-pairs list
I_NSEEN = 4  # DYNA: number of (s, a) pairs in the model
I_ZCUR = 5  # SARSARS: abstract state the agent is in
I_SHAPING = 6  # 1 if shaping is added to the Q update this episode (RNHQL)
I_TRAIN_V = 7  # 1 if V_NN is trained this episode (RNHQL)
I_NF = 8  # number of shaping terms added this episode
I_GOAL = 9  # RNHQLP: the goal state (the optimistic model's BFS root)
N_IVAR = 10

# ---- fvar: float64[N_FVAR], scalar float state
F_PHI = 0  # RNHQL: potential cached when the current state was entered
F_R = 1  # SARSARS: discounted reward since entering the abstract state
F_GK = 2  # SARSARS: gamma^k, k = steps since entering the abstract state
F_FSUM, F_FSQ = 3, 4  # sum and sum of squares of the shaping terms this episode
F_FMEAN, F_FSTD = 5, 6  # shaping mean and std of the last finished episode
F_STEP_V = 7  # RNHQL: V_NN step size, beta / mean |phi|^2
F_RGOAL = 8  # RNHQLP: reward seen on entering G (0: not seen yet)
F_RFREE = 9  # RNHQLP: reward seen on the last free move
F_RFAIL = 10  # DYNA, RNHQLP: reward seen on the last failed move (the model's failure outcome)
N_FVAR = 11
