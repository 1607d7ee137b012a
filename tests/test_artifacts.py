"""Results as code: artifacts carry their provenance, tables render from them, stale ones say so,
and every generated block in the docs matches what its artifact renders to."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from scenarios import artifacts
from scenarios.artifacts import (
    ArtifactError,
    behaviour_digests,
    load_artifact,
    provenance,
    stale_parts,
    write_artifact,
)

REPO = Path(__file__).resolve().parent.parent


def test_behaviour_digests_cover_every_part_and_follow_the_golden_records(tmp_path):
    golden = tmp_path / "g.json"
    records = {"m#d|grid|st-ql|t10|s0|e100": "a", "m#d|physics|st-ql|t10|s0|e100": "b",
               "m#d|physics|fid=noisy|haql|t10|s0|e30": "c"}
    golden.write_text(json.dumps(records))
    before = behaviour_digests(golden)
    assert set(before) == set(artifacts.PARTS) and set(before["grid"]) == {"*", "st-ql"}
    records["m#d|physics|fid=noisy|haql|t10|s0|e30"] = "changed"
    golden.write_text(json.dumps(records))
    after = behaviour_digests(golden)
    assert [p for p in artifacts.PARTS if before[p] != after[p]] == ["physics-noisy"]


def test_a_new_method_leaves_every_table_fresh_and_a_changed_one_names_itself(tmp_path):
    """A table is stale when a method it measured changed; a method added to the golden
    sweep (a new reference method, say) changes no table measured before it."""
    golden = tmp_path / "g.json"
    records = {"m#d|grid|st-ql|t10|s0|e100": "a", "m#d|grid|haql|t10|s0|e100": "b"}
    golden.write_text(json.dumps(records))
    doc = {"behaviour": {"grid": {k: v for k, v in behaviour_digests(golden)["grid"].items()
                                  if k != "*"}}}
    records["m#d|grid|lrta-star|t10|s0|e100"] = "new"
    golden.write_text(json.dumps(records))
    assert stale_parts(doc, behaviour_digests(golden)) == []
    records["m#d|grid|haql|t10|s0|e100"] = "changed"
    golden.write_text(json.dumps(records))
    assert stale_parts(doc, behaviour_digests(golden)) == ["grid (haql)"]
    legacy = {"behaviour": {"grid": behaviour_digests(golden)["grid"]["*"]}}
    assert stale_parts(legacy, behaviour_digests(golden)) == []
    records["m#d|grid|st-ql|t10|s0|e100"] = "changed too"
    golden.write_text(json.dumps(records))
    assert stale_parts(legacy, behaviour_digests(golden)) == ["grid"]


def test_an_artifact_records_the_methods_it_measured_and_a_fixed_policy_check_all(tmp_path):
    """A held-out table of rnh-ql+explore and haql is not stale when R-max changes (it never
    ran it); ``r-max`` is not read into ``mf-r-max``, nor ``rnh-ql`` into ``rnh-ql+``; a
    physics check naming no method depends on every method's records."""
    from scenarios.artifacts import measured

    recorded = {"rnh-ql": "1", "rnh-ql+": "2", "rnh-ql+explore": "3", "haql": "4",
                "r-max": "5", "mf-r-max": "6"}
    table = {"rows": [{"method": "rnh-ql+explore"}, {"method": "HAQL"}], "note": "MF-R-max"}
    got = measured(recorded, table, "python -m scenarios.studies.maps.heldout --methods x")
    assert got == {"rnh-ql+explore": "3", "haql": "4", "mf-r-max": "6"}
    assert measured(recorded, {"p_goal": 0.98}, "rnhql crosscheck maze-1") == recorded
    path = write_artifact("physics-grading.m", "python -m x --methods haql", ["grid"],
                          {"k": 1}, directory=tmp_path)
    assert set(json.loads(path.read_text())["behaviour"]["grid"]) == {"haql"}


def test_an_artifact_records_its_provenance_and_turns_stale_with_the_behaviour(tmp_path):
    path = write_artifact("physics-grading.t", "python -m x --y", ["physics-noisy"],
                          {"k": 1}, directory=tmp_path)
    doc = load_artifact("physics-grading.t", directory=tmp_path)
    assert doc["command"] == "python -m x --y" and doc["data"] == {"k": 1}
    assert set(doc["behaviour"]) == {"physics-noisy"} and doc["date"] and doc["code_version"]
    assert path.name == "physics-grading.t.json"
    now = behaviour_digests()
    assert stale_parts(doc, now) == []
    assert "Stale" not in provenance(doc, now)
    moved = {**now, "physics-noisy": "000000000000"}
    assert stale_parts(doc, moved) == ["physics-noisy"]
    text = provenance(doc, moved)
    assert "**Stale**" in text and "python -m x --y" in text


def test_bad_artifacts_are_clear_errors(tmp_path):
    with pytest.raises(ArtifactError, match="missing"):
        load_artifact("nope", directory=tmp_path)
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(ArtifactError, match="unreadable"):
        load_artifact("bad", directory=tmp_path)
    (tmp_path / "other.json").write_text('{"format": "something else"}')
    with pytest.raises(ArtifactError, match="not an"):
        load_artifact("other", directory=tmp_path)
    with pytest.raises(ArtifactError, match="unknown behaviour part"):
        write_artifact("x.y", "cmd", ["physics-rough"], {}, directory=tmp_path)


def test_every_generated_block_in_the_docs_matches_its_artifact():
    """``cog --check``: a table in the README or docs/ that differs from what its artifact
    renders (edited by hand, or its artifact re-measured without ``cog -r``) fails here."""
    from cogapp import Cog

    pages = [p for p in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
             if "[[[cog" in p.read_text()]
    assert pages, "no generated blocks found"
    code = Cog().main(["cog", "--check", "-I", str(REPO), *map(str, pages)])
    assert code == 0, "generated blocks are out of date: run `cog -r README.md docs/*.md`"


def test_editing_the_study_script_marks_its_artifact_stale(tmp_path):
    """The behaviour digests cover the learners and worlds, not a study's own settings (an
    ablation row's switches): the artifact hashes its study script too."""
    from scenarios.artifacts import load_artifact, stale_parts, write_artifact

    study = tmp_path / "study.py"
    study.write_text("ROWS = [('a', 1)]\n")
    write_artifact("demo.x", "python -m demo", ["grid"], {"rows": 1}, directory=tmp_path,
                   study=study)
    doc = load_artifact("demo.x", directory=tmp_path)
    assert stale_parts(doc) == []
    study.write_text("ROWS = [('a', 2)]\n")
    assert stale_parts(doc) == [f"the study {study}"]


def test_a_study_moved_or_its_imports_rearranged_stays_fresh(tmp_path):
    """The study hash is of its code without import statements and docstrings: moving a
    module (every import of it rewritten), hoisting an import or editing a comment or a
    docstring changes no table, while the code that measures does."""
    from scenarios.artifacts import study_code_digest

    before = ("import math\n\n\ndef rows():\n    from a.b import c  # lazy\n"
              "    return [('a', math.pi, c)]\n")
    moved = ('"""The study."""\n\nimport math\n\nfrom a.b.c2 import c\n\n\ndef rows():\n'
             '    """Its rows."""\n    # the rows\n    return [(\'a\', math.pi, c)]\n')
    assert study_code_digest(before) == study_code_digest(moved)
    assert study_code_digest(before) != study_code_digest(moved.replace("'a'", "'b'"))
    edited = before.replace("return", "x = 1\n    return")
    assert study_code_digest(before) != study_code_digest(edited)


def test_an_artifact_written_before_the_code_hash_is_checked_by_its_bytes(tmp_path):
    import hashlib

    from scenarios.artifacts import study_changed

    study = tmp_path / "study.py"
    study.write_text("ROWS = 1\n")
    old = {"path": str(study), "sha256": hashlib.sha256(study.read_bytes()).hexdigest()}
    assert not study_changed(old)
    study.write_text("ROWS = 1  # a comment is a change of bytes\n")
    assert study_changed(old)


def test_an_artifact_records_the_machine_load_and_a_busy_machine_is_named():
    from scenarios.artifacts import busy_note

    quiet = {"name": "scaling.x", "machine": {"cores": 2, "load_1min": 1.5}}
    busy = {"name": "scaling.x", "machine": {"cores": 2, "load_1min": 3.9}}
    untimed = {"name": "reward-design.x", "machine": {"cores": 2, "load_1min": 3.9}}
    assert busy_note(quiet) == "" and busy_note({"name": "scaling.x"}) == ""
    assert busy_note(untimed) == "", "a table without timings needs no busy note"
    assert "load 3.9 on 2 cores" in busy_note(busy)


def test_artifact_names_are_checked_before_any_work():
    import argparse

    from scenarios.artifacts import check_artifact_name

    p = argparse.ArgumentParser()
    check_artifact_name(p, "paper-50-noisy")
    for bad in ("A", "a b", "../x", "", "x" * 65, "a.b"):
        with pytest.raises(SystemExit) as err:
            check_artifact_name(p, bad)
        assert err.value.code == 2


def test_rows_of_several_artifacts_make_one_table_with_each_provenance(tmp_path, monkeypatch):
    from scenarios.artifacts import rendered_rows

    monkeypatch.setattr(artifacts, "RESULTS_DIR", tmp_path)
    for name, mof in (("exact", 0.0), ("noisy", 0.0245)):
        data = {"scenario": "paper-50", "fidelity": name, "repeats": 20, "seed": 0,
                "pairs": 8, "primitives": 160, "multi_outcome_fraction": mof,
                "mean_entropy_bits": 0.01, "mean_bump_probability": 0.06}
        write_artifact(f"aliasing.{name}", f"rnhql aliasing --fidelity {name}", ["grid"],
                       data, directory=tmp_path)
    monkeypatch.setattr(artifacts, "load_artifact",
                        lambda n, directory=tmp_path: load_artifact(n, directory))
    text = rendered_rows(["aliasing.exact", "aliasing.noisy"])
    assert text.count("| paper-50 |") == 2 and "0.0245" in text
    assert text.count("<sub>Generated from") == 2


def test_every_committed_artifact_records_the_study_that_wrote_it():
    """An artifact without its study's code hash cannot go stale when that study changes
    (the report would call it fresh for ever): every committed one carries it."""
    from scenarios.artifacts import RESULTS_DIR, artifact_names, load_artifact

    missing = [n for n in artifact_names(RESULTS_DIR)
               if "code_sha256" not in load_artifact(n).get("study", {})]
    assert missing == [], f"re-run these with --artifact: {missing}"


def test_a_studys_hash_covers_the_study_code_it_computes_with():
    """The ladder's numbers come from its predictivity statistics too, the crosscheck's from
    its IR-SIM world: a change there stales the table as a change of the study does."""
    from scenarios.artifacts import ROOT, study_changed, study_digest

    ladder = study_digest(ROOT / "scenarios/studies/ladder/continuous_vs_grid.py")
    assert "scenarios/studies/ladder/predictivity.py" in ladder["with"]
    assert not study_changed(ladder)
    edited = {**ladder, "with": {**ladder["with"],
                                 "scenarios/studies/ladder/predictivity.py": "0" * 64}}
    assert study_changed(edited)
    crosscheck = study_digest(ROOT / "sim/physics/crosscheck/agreement.py")
    assert "sim/physics/crosscheck/irsim_world.py" in crosscheck["with"]
    assert study_digest(ROOT / "scenarios/bench/plain.py")["with"] == {}  # nothing beyond
