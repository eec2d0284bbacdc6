"""dicstream.read_results on a results folder: its JSON files and its field CSV files as the
arrays correlate returns."""

import json
import shutil

import numpy as np
import pytest

import dicstream


def test_a_results_folder_reads_back(cli, tmp_path, sample5):
    reference, deformed = sample5
    out = tmp_path / "correlate"
    cli("correlate", reference, deformed, "--out", out, "--threads", 2)
    run = tmp_path / "run"
    (run / "fields").mkdir(parents=True)
    shutil.copy(out / "summary.json", run / "summary.json")
    shutil.copy(out / "field_0001.csv", run / "fields" / "field_000001.csv")
    (run / "identification.json").write_text(json.dumps({"fits": []}))
    results = dicstream.read_results(run)
    assert results["summary"] == json.loads((out / "summary.json").read_text())
    assert results["identification"] == {"fits": []}
    assert results["frames"] is None
    field = results["fields"]["field_000001"]
    ours = dicstream.correlate(*(dicstream.read_image(p) for p in sample5), threads=2)
    np.testing.assert_allclose(field["u"], ours["u"].ravel(), rtol=0, atol=1.01e-6)
    assert list(field["status"]) == list(ours["status"].ravel())


def test_not_a_folder_is_refused(tmp_path):
    with pytest.raises(ValueError, match="not a folder"):
        dicstream.read_results(tmp_path / "nothing")
