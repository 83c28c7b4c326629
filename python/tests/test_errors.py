"""Bad options and bad files raise exceptions that name them."""

import pytest

import sitar


def test_an_unknown_option_is_a_type_error_naming_it(synthetic):
    ref, est = synthetic
    with pytest.raises(TypeError, match="'alignn'"):
        sitar.ape("tum", ref, est, alignn=True)
    with pytest.raises(TypeError, match="'delta'"):
        sitar.ape("tum", ref, est, delta=3)  # an rpe option


def test_a_bad_value_names_the_option(synthetic):
    ref, est = synthetic
    with pytest.raises(ValueError, match="pose_relation: invalid choice 'bogus'"):
        sitar.ape("tum", ref, est, pose_relation="bogus")
    with pytest.raises(ValueError, match="delta_unit"):
        sitar.rpe("tum", ref, est, delta_unit="x")
    with pytest.raises(ValueError, match="n_to_align"):
        sitar.ape("tum", ref, est, align=True, n_to_align="all")
    with pytest.raises(sitar.SitarError, match="n_to_align must be -1"):
        sitar.ape("tum", ref, est, align=True, n_to_align=0)
    with pytest.raises(ValueError, match="unknown format 'tumm'"):
        sitar.ape("tumm", ref, est)


def test_a_bad_line_names_the_file_and_line(synthetic, tmp_path):
    ref, _ = synthetic
    bad = tmp_path / "bad.txt"
    bad.write_text("1.0 0 0 0 0 0 0 1\n1.1 0 0 0 0 0 0 1\n1.2 0 zero 0 0 0 0 1\n")
    with pytest.raises(sitar.SitarError, match=rf"{bad}:3:"):
        sitar.ape("tum", ref, bad)


def test_a_missing_file_is_file_not_found_naming_it(synthetic, tmp_path):
    ref, _ = synthetic
    missing = tmp_path / "missing.txt"
    with pytest.raises(FileNotFoundError, match="missing.txt"):
        sitar.rpe("tum", ref, missing)


def test_no_common_stamps_is_an_error_and_dropped_poses_a_warning(synthetic, tmp_path):
    ref, est = synthetic
    with pytest.raises(sitar.SitarError, match="found no matching timestamps"):
        sitar.ape("tum", ref, est, t_offset=1000.0)
    # Every tenth estimate pose 0.05 s off the reference's stamps: 10 of 100 dropped.
    lines = est.read_text().splitlines()[:100]
    shifted = tmp_path / "shifted.txt"
    with open(shifted, "w") as out:
        for i, line in enumerate(lines):
            t, rest = line.split(" ", 1)
            out.write(f"{float(t) + (0.05 if i % 10 == 0 else 0.0):.6f} {rest}\n")
    with pytest.warns(sitar.SitarWarning, match="10 dropped"):
        doc = sitar.ape("tum", ref, shifted)
    assert doc["pairing"]["estimate_dropped"] == 10 and len(doc["errors"]) == 90
