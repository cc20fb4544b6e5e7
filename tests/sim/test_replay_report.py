"""The console side shared by every ``evomotion replay`` body."""

import json
from pathlib import Path

from evomotion.sim.replay_report import report_replay


def test_a_skipped_video_is_one_note_on_stderr_and_dropped(capsys):
    done, video = report_replay({"a": 1}, "no GL backend", Path("v.mp4"), json_out=False)
    out, err = capsys.readouterr()
    assert (done, video, out) == (False, None, "")
    assert err == "video skipped: no GL backend\n"


def test_json_prints_the_summary_alone_on_stdout(capsys):
    done, video = report_replay({"a": 1, "b": [2.5]}, None, Path("v.mp4"), json_out=True)
    out, err = capsys.readouterr()
    assert (done, video, err) == (True, Path("v.mp4"), "")
    assert json.loads(out) == {"a": 1, "b": [2.5]}


def test_plain_text_leaves_the_printing_to_the_caller(capsys):
    assert report_replay({}, None, None, json_out=False) == (False, None)
    assert capsys.readouterr() == ("", "")
