"""Study ``humanoid-walk``: a closed-loop omnidirectional walk controller for the NAO (or
another biped, ``--robot``), evolved by ARS (or OpenAI-ES, PGPE, SNES, CMA-ES) from a fitted
walk engine through the run loop. It was ``humanoid-omniwalk`` until it became the walk's
default (issue 34); the open-loop walk it replaced is ``--preset open-loop`` (the study
``humanoid-walk-open-loop``, package ``studies/humanoid_walk``).

``evomotion run humanoid-walk`` evolves the controller of :mod:`.controller` (a phase
tape modulated by the command ``(vx, vy, ω)`` plus feedback from the IMU, the joints and the
feet) over random command schedules in perturbed, pushed worlds; beside the run's files it
writes ``policy.npz``, ``policy.py``, ``policy.onnx`` and ``policy.json``.
``evomotion humanoid-walk compare RUN`` measures it against the walk engine it started
from. See docs/humanoid-walk.md.
"""

from __future__ import annotations

from pathlib import Path

import typer

from evomotion.studies.base import Study, lazy_hook
from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig, OmniWalkProblem
from evomotion.studies.policy_search import policy_algorithms
from evomotion.studies.view import StudyView, lazy

ARTIFACTS = "evomotion.studies.humanoid_omniwalk.artifacts"

cli = typer.Typer(help="A closed-loop omnidirectional walk (the NAO, or --robot op3).",
                  no_args_is_help=True)


@cli.command("compare")
def compare_cmd(run: Path = typer.Argument(..., help="a humanoid-walk run folder"),
                worlds: int = typer.Option(100, "--worlds", help="unseen perturbed worlds "
                                                                 "(1 to 10000)"),
                duration: float = typer.Option(60.0, "--duration", help="seconds of random "
                                               "commands per world (0.5 to 600)"),
                seed: int = typer.Option(0, "--seed", help="seed of the worlds (>= 0)"),
                capture_gain: float = typer.Option(None, "--capture-gain", help="the capture "
                                                   "step's gain over the run's (0 to 3; 0 "
                                                   "none; the NAO)"),
                json_out: bool = typer.Option(False, "--json", help="JSON on stdout")) -> None:
    """The evolved controller beside the walk engine it started from, on the same worlds."""
    from evomotion.studies.humanoid_omniwalk.compare import compare_command

    typer.echo(compare_command(run, worlds=worlds, duration_s=duration, seed=seed,
                               json_out=json_out, capture_gain=capture_gain))




NAO_DEFAULTS = {"problem": {"symmetric": True, "capture_gain": 1.0, "sigma_yaw_rps": 0.15}}

STUDY = Study(
    name="humanoid-walk",
    description="A closed-loop omnidirectional NAO walk (or another biped's, --robot): a "
                "command-modulated gait tape plus sensor feedback, evolved by ARS over random "
                "commands in pushed worlds.",
    problem_config=OmniWalkConfig,
    make_problem=OmniWalkProblem,
    # ARS V2-t (Mania et al. 2018), 16 directions, the best 8, noise 0.005: noise 0.02 (0.6
    # rad over the 885 parameters) knocked every perturbed walk over and the centre sank; step
    # 0.002 stalled near generation 120 and drifted; step 0.001 keeps improving for 300
    # generations (all measured: docs/humanoid-walk.md)
    # command feedback started at the probe's forward-lean gain: survival 68 / 62 / 65 %
    # against 57 / 54 / 63 % without it (3 seeds), speed error 0.031-0.038 against 0.027-0.032
    # m/s (docs/humanoid-walk.md); --set problem.command_feedback=false for the former
    # two training episodes per direction (2026-12-05): survival alike (68 / 63 / 60 %
    # against 68 / 62 / 65 %), tracking errors a fifth lower, 14 of 18 top speeds met against
    # 9, in 10.6-11.9 min on 2 cores (one episode: 5-6.5 min); docs/humanoid-walk.md
    defaults={"algorithm": {"name": "ars", "pop_size": 32, "step_size": 0.001,
                            "noise_std": 0.005, "top_directions": 8},
              "run": {"generations": 300, "checkpoint_every": 20},
              "problem": {"command_feedback": True, "command_feedback_start": 0.1,
                          "episodes": 2}},
    # the NAO (its own robot, "" or "nao"): mirror-symmetric controllers (2026-12-06, ninth
    # session; 489 numbers instead of 978; needs the robot's mirror capability): every top
    # speed met on 3 seeds against 14 of 18, steady speed / yaw-rate errors 13 / 11-14 %
    # against 15-19 / 19-20 %, survival 62 / 60 / 66 % against 68 / 63 / 60 %
    # (docs/humanoid-walk.md); --set problem.symmetric=false for the former.
    # Capture steps by leg odometry on top (2026-12-06, fifteenth session, once the NAOqi
    # runner and the policy player ran them): survival 74 / 73 / 73 % against 62 / 60 / 66 %
    # on the same seeds, held-command speed error 13.0 / 9.6 / 12.9 %; --set
    # problem.capture_gain=0 for the former.
    # A yaw-rate kernel half as wide (2026-12-07, seventeenth and eighteenth sessions): the
    # yaw-rate error over every window 21 / 18 % against 27 / 31 % (steady 8 / 9 % against
    # 15 / 18 %) on seeds 0 / 1 retrained on one host, survival 70 / 68 % against 67 / 70 %,
    # the speed error alike; seed 2 at 0.15: 23 % (11 %), 75 % (docs/humanoid-walk.md); --set
    # problem.sigma_yaw_rps=0.3 for the former.
    # The dm humanoid (2026-12-06): with the NAO's defaults it learned to stand; from the
    # engine setting that walked furthest in the scan, on forward commands alone in the
    # nominal world, 600 generations walk 0.23-0.25 m/s at 0.3 on every seed (the same doc).
    # Without the yaw-rate term (2026-12-07, twentieth session): on forward commands alone it
    # gave a standing robot a third of the score for nothing (its zero yaw rate), and seed 0
    # retrained on this VM drifted to standing after generation 21 (its export 0.16 m/s at
    # 0.2, fell at 0.3); with yaw_share 0 the centre kept improving, 300 generations
    robot_defaults={"": NAO_DEFAULTS, "nao": NAO_DEFAULTS, "dm-humanoid": {
        "run": {"generations": 300},
        "problem": {"sway_m": 0.008, "sway_phase_rad": 1.57, "step_height_m": 0.005,
                    "perturb": False, "push_max_ns": 0.0, "vx_min": 0.15, "vx_max": 0.3,
                    "vy_max": 0.05, "yaw_rate_max": 0.2,
                    "command_weights": [1.0, 0.0, 0.0, 0.0, 0.0], "yaw_share": 0.0}}},
    # the open-loop walk (a tape of 14 gait parameters, forward only, CMA-ES) is a problem of
    # another kind, so its preset is its own study
    preset_studies={"open-loop": "humanoid-walk-open-loop"},
    preset_notes={"open-loop": "the open-loop walk it replaced (a tape of 14 gait "
                               "parameters, forward only, CMA-ES; the study "
                               "humanoid-walk-open-loop)"},
    core_algorithms=(),
    algorithms=policy_algorithms(),
    on_checkpoint=lazy_hook(ARTIFACTS, "write_policy"),
    finalize=lazy_hook(ARTIFACTS, "finalize"),
    best_record=lazy_hook("evomotion.studies.policy_files", "best_record"),
    replay=None,
    replay_run=lazy("evomotion.studies.humanoid_omniwalk.replay", "replay_walk_command"),
    cli=cli,
    view=StudyView(drive=True),  # the studio drives the controller live
    smoke=("problem.duration_s=1.0", "problem.eval_episodes=1", "problem.episodes=1",
           "problem.threads=1", "algorithm.pop_size=4", "algorithm.top_directions=0"),
)
