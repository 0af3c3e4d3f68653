"""Regenerate the example figures of results/: plan.png, motion.png, simulation.png and roll.gif.

Run: python scripts/make_figures.py   (the same figures as the commands

    rollplan plan --to 0.5 0.7 --psi 0.8 --steps 2 --plot results/plan.png
    rollplan plan --to 0 0.1 --psi 0.3 --duration 10 --json plan.json --plot results/motion.png
    rollplan simulate plan.json --robot heavier.toml --plot results/simulation.png
    rollplan animate plan.json --out results/roll.gif --frames 40 --fps 8 (smaller frames)

where heavier.toml is the default robot with 5 % more total mass, so the simulation misses.)
"""

from dataclasses import replace
from pathlib import Path

from rollplan import actuate, default_robot, plan, simulate_rotors
from rollplan.io import save_figure
from rollplan.plots.animation import make_animation
from rollplan.plots.motion import plot_motion, plot_simulation
from rollplan.plots.plan import plot_plan
from rollplan.progress import Progress

OUT = Path(__file__).resolve().parent.parent / "results"

if __name__ == "__main__":
    p = plan((0.5, 0.7, 0.8), 2, k=2.5)
    save_figure(plot_plan(p, p.sample()), OUT / "plan.png")
    robot = default_robot()
    pm = plan((0.0, 0.1, 0.3), robot=robot)
    motion = actuate(pm, robot, duration=10.0)
    save_figure(plot_motion(motion, pm, pm.sample(), "m"), OUT / "motion.png")
    heavier = replace(robot, mass_total=robot.mass_total * 1.05)
    sim = simulate_rotors(heavier, motion.series.time, motion.series.rotor_rates, pm.goal)
    miss = sim.position_error * heavier.radius
    title = (f"rotor-driven simulation, robot with 5 % more total mass: arrival error {sim.arrival_error:.2e} "
             f"(Euclidean norm; lengths in R, angles in rad),\nposition error {miss:.2e} m")
    save_figure(plot_simulation(sim.series, pm.goal, motion.series.state, heavier, title),
                OUT / "simulation.png")
    exact = simulate_rotors(robot, motion.series.time, motion.series.rotor_rates, pm.goal)
    with Progress(unit="frames") as progress:
        make_animation(exact.series, robot, pm.goal, OUT / "roll.gif", frames=40,
                       fps=8, progress=progress, dpi=80)
    print(f"wrote {OUT / 'plan.png'}, motion.png, simulation.png, roll.gif")
