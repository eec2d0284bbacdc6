"""dicstream.identify against `dicstream identify --json` on Treloar's data: the same fits,
ranked the same, with the same parameters; bad data refused with the reader's rules."""

import json
import re

import numpy as np
import pytest

import dicstream
from conftest import shared_data

# Enough models to rank, few enough for a quick test.
MODELS = "neo-hookean,mooney,yeoh,ogden:2"


def treloar():
    folder = shared_data("treloar1944")
    return {
        case: np.loadtxt(folder / f"{file}.csv", delimiter=",", skiprows=1)
        for case, file in [("uniaxial", "uniaxial"), ("biaxial", "equibiaxial"), ("pure_shear", "pure_shear")]
    }, folder


def test_the_ranking_and_parameters_are_the_clis(cli):
    data, folder = treloar()
    done = cli(
        "identify", "--uniaxial", folder / "uniaxial.csv", "--biaxial", folder / "equibiaxial.csv",
        "--pure-shear", folder / "pure_shear.csv", "--model", MODELS, "--json",
    )
    expected = json.loads(done.stdout)
    ours = dicstream.identify(**data, model=MODELS)
    assert [f["model"] for f in ours["fits"]] == [f["model"] for f in expected["fits"]]
    assert [f["rank"] for f in ours["fits"]] == [f["rank"] for f in expected["fits"]]
    assert len(ours["fits"]) == 4
    # The same numbers: the same code on the same values.
    assert ours == expected
    best = ours["fits"][0]
    assert set(best) >= {"params", "stderr", "rms_mpa", "aic", "warning"}


def test_pairs_and_data_frames_are_the_arrays():
    data, _ = treloar()
    arrays = dicstream.identify(uniaxial=data["uniaxial"], model="mooney")
    pair = dicstream.identify(uniaxial=(data["uniaxial"][:, 0], data["uniaxial"][:, 1]), model="mooney")
    assert pair == arrays
    pandas = pytest.importorskip("pandas", reason="pandas not installed: data frames not tested")
    frame = pandas.DataFrame(data["uniaxial"], columns=["stretch", "nominal_stress_mpa"])
    assert dicstream.identify(uniaxial=frame, model="mooney") == arrays


def test_bad_data_is_refused():
    good = np.array([[1.1, 0.1], [1.2, 0.2], [1.3, 0.3]])
    with pytest.raises(ValueError, match=re.escape("no data: give at least one of")):
        dicstream.identify()
    with pytest.raises(ValueError, match=re.escape("reading uniaxial data")):
        dicstream.identify(uniaxial=good[::-1])
    with pytest.raises(ValueError, match=re.escape("give an (n, 2) array")):
        dicstream.identify(uniaxial=np.ones((3, 3)))
    with pytest.raises(ValueError, match="unknown|model"):
        dicstream.identify(uniaxial=good, model="no-such-model")
    with pytest.raises(ValueError, match=re.escape("reading general biaxial data: row 1")):
        dicstream.identify(biaxial_general=[[float("nan"), 1.0, 0.1, 0.1]])
