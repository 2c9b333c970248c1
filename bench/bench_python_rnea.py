# Per-call time of rnea from Python on the UR5 (config/robots/ur5.yaml, the model of bench_multibody's UR5_RNEA):
#   build/pyenv/bin/python bench/bench_python_rnea.py jointsim     (after scripts/python-test.sh)
#   PYENV_WITH_PIN/bin/python bench/bench_python_rnea.py pin       (Pinocchio's bindings, pip install pin; its UR5 URDF)
# The overhead of the bindings is this figure minus UR5_RNEA of bench/bench_multibody.
import timeit, numpy as np, sys
q = np.array([0.1,-1.2,1.2,-1.5,-1.57,0.3]); qd = np.full(6,0.2); qdd = np.full(6,0.1)
if sys.argv[1] == "jointsim":
    import jointsim
    m = jointsim.load_robot("config/robots/ur5.yaml")
    f = lambda: jointsim.rnea(m, q, qd, qdd)
else:
    import pinocchio as pin
    m = pin.buildModelFromUrdf("config/robots/ur5.urdf"); d = m.createData()
    f = lambda: pin.rnea(m, d, q, qd, qdd)
for _ in range(3):
    n = 200000
    t = min(timeit.repeat(f, number=n, repeat=5)) / n
    print(sys.argv[1], "rnea per call from Python: %.3f us" % (t*1e6))
