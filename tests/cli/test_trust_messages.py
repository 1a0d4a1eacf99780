"""Messages that say what happened in the words of the interface the user called (issue 34, item 6)."""

from __future__ import annotations

import importlib
import json
import shlex
import warnings
from pathlib import Path

import numpy as np
import pytest

import isolator
import isolator.sweep.runner as runner
from conftest import base_dict, make, run_command
from isolator.errors import ParameterError
from isolator.simulation.band import Band
from isolator.sweep import sweep

SWEEP = ["sweep", "paper-table-3-2", "--scale", "isolators[*].damping=0.5:1.14:64", "--workers", "2",
         "--chunk-size", "8"]


def test_a_band_read_back_is_named_as_the_run_it_came_from():
    """A run's own band written out and given to another run is that run's peaks, not the new run's."""
    written = Band.own(0.05).resolved(np.array([1e-5, 2e-5, 3e-5, 1e-6, 2e-6, 3e-6])).to_dict()
    band = Band.from_dict(json.loads(json.dumps(written)), "--band-json")
    assert list(band.widths.values()) == pytest.approx([5e-7, 1e-6, 1.5e-6, 5e-8, 1e-7, 1.5e-7])
    assert "own peak" not in band.describe()
    assert band.how() == "5 % of the peaks of the run it was written from"
    assert band.resolve(np.ones(6)) == pytest.approx(list(band.widths.values()))  # the widths as written


def test_an_interrupted_sweep_says_what_it_kept_and_how_to_resume(tmp_path: Path, capsys, monkeypatch):
    original = runner.run_chunks

    def interrupted(chunks, executor, in_flight, done, *rest):
        def after_one(result):
            done(result)
            raise KeyboardInterrupt

        return original(chunks, executor, in_flight, after_one, *rest)

    monkeypatch.setattr(importlib.import_module("isolator.sweep.sweep"), "run_chunks", interrupted)
    out = tmp_path / "rows.csv"
    status, _, err = run_command([*SWEEP, "--out", str(out), "--force"], capsys)
    assert status == 130
    # a loaded machine may take the 2 s after which progress lines start (isolator.sweep.progress.DELAY)
    err = [line for line in err if not line.startswith("isolator sweep: ")]
    assert len(err) == 1
    assert err[0].startswith(f"isolator: interrupted: 8 row(s) kept in {out}; continue with: isolator sweep ")
    assert err[0].endswith(f"--out {out} --resume")
    assert "--force" not in err[0]
    monkeypatch.undo()
    command = shlex.split(err[0].split("continue with: ")[1])[1:]  # as a shell would read it
    status, text, err = run_command(command, capsys)
    assert status == 0, err
    assert "designs: 64 (56 run now, 8 from the file)" in text


def test_one_vocabulary_per_interface(tmp_path: Path, capsys):
    out = tmp_path / "rows.csv"
    sweep("paper-table-3-2", scale={"isolators[*].damping": [1.0, 2.0]}, workers=1, out=out)
    other = ["sweep", "paper-table-3-2", "--scale", "isolators[*].damping=1,3", "--workers", "1", "--out", str(out),
             "--resume"]
    status, _, err = run_command(other, capsys)
    assert status == 2
    assert "--force starts again" in err[0]
    assert "force=True" not in err[0]
    assert err[0].startswith("isolator: error: --out: ")
    with pytest.raises(ParameterError) as info:
        sweep("paper-table-3-2", scale={"isolators[*].damping": [1.0, 3.0]}, workers=1, out=out, resume=True)
    assert "force=True starts again" in str(info.value)
    assert "--force" not in str(info.value)


def test_a_study_called_from_python_prints_nothing(tmp_path: Path, capsys):
    from studies.tradeoff import run_tradeoff_study

    run_tradeoff_study(tmp_path, make(base_dict()), stiffness=[0.5, 1.0], damping=[1.0, 2.0], workers=1)
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err == ""
    run_tradeoff_study(tmp_path / "again", make(base_dict()), stiffness=[0.5, 1.0], damping=[1.0, 2.0], workers=1,
                       progress=True)
    captured = capsys.readouterr()
    assert captured.out == ""  # progress is not a result
    assert captured.err.strip()  # on stderr


def test_static_equilibrium_is_deprecated_for_a_release_with_its_arguments_checked():
    scenario = isolator.load_scenario("paper-table-3-2")
    layout = isolator.ParameterLayout.of(scenario)
    model = isolator.get_model(layout)
    with pytest.warns(DeprecationWarning, match=r"isolator.static_equilibrium is deprecated .*isolator.linearise"):
        from isolator import static_equilibrium
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        equilibrium = static_equilibrium(model, layout.pack(scenario), scenario.initial_positions())
    expected = isolator.linearise(scenario, positions=scenario.initial_positions()).equilibrium
    np.testing.assert_allclose(equilibrium.pose, expected.pose, rtol=1e-9, atol=1e-15)
    with pytest.raises(ParameterError, match=r"^p: must be \d+ finite numbers, got 1"):
        static_equilibrium(model, [1.0], scenario.initial_positions())
    with pytest.raises(ParameterError, match=r"^model: must be an isolator Model"):
        static_equilibrium("exact", layout.pack(scenario), scenario.initial_positions())
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        isolator.nothing  # noqa: B018
