"""The Python API in a few lines: run with the venv's Python from any folder, `python examples/api.py`."""

import rollplan

p = rollplan.plan(target=(0.0, 1.0, 0.0), steps=1, k=2.5)
print(p.a, p.b, p.gamma, p.branch)  # 0.300429 R, 0.300429 R, 0.931883 rad, branch m = 0
print(p.final, p.residual)          # State(u_a, v_a, psi, u_o, v_o); residual by an independent RK8 run
traj = p.sample()                   # Trajectory: s (theta), state (N, 5), segment, contact points

problem = rollplan.Problem(goal=(0.5, 0.3, 0.4), k=2.5)       # one problem, two methods
gp = rollplan.solve(problem, method="geometric")              # exact figure-eight plan
oc = rollplan.solve(problem, method="collocation")            # optimal control on the same model
print(gp.path_length, oc.path_length)

robot = rollplan.default_robot()
pm = rollplan.plan((0.0, 0.1, 0.0), robot=robot)     # lengths in metres
motion = rollplan.actuate(pm, robot, duration=10.0)  # .series: a TimeSeries of omega, rotor rates, torques
print(abs(motion.series.rotor_torques).max(), "N m")
