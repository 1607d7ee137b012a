"""``rnhql aliasing``: no aliasing at exact, some at noisy, written as promised."""

from __future__ import annotations

import json

from scenarios.cli import main
from scenarios.recording.file import verify_recording


def test_aliasing_is_zero_at_exact_and_not_at_noisy(tmp_path, capsys):
    for fid in ("exact", "noisy"):
        out = tmp_path / fid
        assert main(["aliasing", "paper-40", "--fidelity", fid, "--repeats", "4",
                     "--out", str(out)]) == 0
        got = json.loads((out / "aliasing.json").read_text())
        assert got["fidelity"] == fid and got["pairs"] == len(got["per_pair"])
        assert (out / "aliasing.png").stat().st_size > 1000
        assert verify_recording(out / "aliasing.rrd")[0]
        if fid == "exact":
            assert got["multi_outcome_fraction"] == 0.0 and got["mean_entropy_bits"] == 0.0
        else:
            assert got["multi_outcome_fraction"] > 0.0
    assert "multi_outcome_fraction" in capsys.readouterr().out


def test_aliasing_bad_input_is_one_line(tmp_path, capsys):
    assert main(["aliasing", "paper-40", "--fidelity", "wobbly", "--out", str(tmp_path)]) == 2
    assert main(["aliasing", "paper-40", "--repeats", "0", "--out", str(tmp_path)]) == 2
    assert "Traceback" not in capsys.readouterr().err
