"""The studio asks each study for its view (issue 32): it names no study, and every study's
declared view is well formed; a study reads a run's files only through the studio's bounds."""

from __future__ import annotations

from pathlib import Path

import pytest

from evomotion.errors import InputError
from evomotion.studies import STUDIES, get_study
from evomotion.studies.view import Frames, NothingYetError, Scene, StudyView
from evomotion.studio import views

STUDIO = Path(views.__file__).parent


def test_the_studio_names_no_study():
    source = {p.name: p.read_text() for p in STUDIO.glob("*.py")}
    for name, target in STUDIES.items():
        package = target.split(":")[0].rsplit(".", 1)[0]
        for file, text in source.items():
            assert f'"{name}"' not in text, (file, name)
            assert package not in text, (file, package)


@pytest.mark.parametrize("name", list(STUDIES))
def test_every_declared_view_is_well_formed(name):
    view = get_study(name).view
    if view is None:
        return
    assert isinstance(view, StudyView)
    assert view.motions or view.frames is not None or view.table or view.archive_map or \
        view.drive or view.played is not None
    assert view.frames is None or callable(view.frames)
    assert view.played is None or callable(view.played)
    assert view.genome_motion is None or (callable(view.genome_motion) and view.motions)
    if view.scene is not None:
        assert isinstance(view.scene, Scene) and view.scene.name != "nao"
        assert callable(view.scene.load_model) and callable(view.scene.initial_state)


def test_run_files_say_what_is_missing_and_keep_the_bounds(tmp_path, monkeypatch):
    files = views.StudioRunFiles("functions", tmp_path)
    with pytest.raises(NothingYetError, match="population.bin"):
        files.history()
    with pytest.raises(NothingYetError, match="plan.json"):
        files.json("plan.json", "plan")
    assert files.stats() == {}
    (tmp_path / "plan.json").write_text("[" * 10 + "]" * 10)
    monkeypatch.setattr(views, "MAX_JSON_BYTES", 8)
    with pytest.raises(InputError, match="plan.json"):
        files.json("plan.json", "plan")


def test_frames_of_a_study_step_through_figures(tmp_path):
    from evomotion.api import run

    out = tmp_path / "g"
    run("grid-path", {"run": {"generations": 3, "history_every": 1},
                      "algorithm": {"pop_size": 16}}, out)
    frames = get_study("grid-path").view.frames(views.StudioRunFiles("grid-path", out))
    assert isinstance(frames, Frames) and frames.count >= 3
    fig, caption = frames.draw(frames.count - 1)
    assert fig.axes and caption.startswith("generation ")


def test_motions_sort_by_their_numbers_and_durations_read_for_people(tmp_path):
    """Issue 35: the kick's motions sorted as text (+0, +10, ..., -10), a 0.039 s run read
    "0.0 s"."""
    from evomotion.studio.pages import duration_text

    (tmp_path / "kicks").mkdir()
    for a in ("-30", "-20", "-10", "+0", "+10", "+20", "+30"):
        (tmp_path / "kicks" / f"aim_{a}.motion").write_text("#WEBOTS_MOTION,V1.0\n")
    (tmp_path / "best.motion").write_text("#WEBOTS_MOTION,V1.0\n")
    assert views.motions_of(tmp_path) == ["best.motion"] + [
        f"kicks/aim_{a}.motion" for a in ("-30", "-20", "-10", "+0", "+10", "+20", "+30")]
    assert [duration_text(s) for s in (0.039, 12.34, 59.9, 75, 7322, float("nan"))] == \
        ["0.039 s", "12.3 s", "59.9 s", "1 min 15 s", "2 h 02 min", ""]
