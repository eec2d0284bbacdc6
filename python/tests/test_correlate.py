"""dicstream.correlate against `dicstream correlate` on the same DIC Challenge pair: the same
field node by node and the same summary; its input conversions; bad input refused with the
CLI's message."""

import json
import re

import numpy as np
import pytest

import dicstream

# The CSV columns (field_NNNN.csv) and their printed decimals: Python's arrays must round to
# the CLI's text.
CSV_DECIMALS = {
    "x": 0, "y": 0, "u": 6, "v": 6, "exx": 7, "eyy": 7, "exy": 7, "score": 5, "iterations": 0,
    "du_dx": 7, "du_dy": 7, "dv_dx": 7, "dv_dy": 7,
}

# Entries of a frame in summary.json that are the CLI's own (its file, index and time).
CLI_ONLY = {"index", "file", "elapsed_ms"}


def cli_field(cli, tmp_path, reference, deformed, *flags):
    out = tmp_path / "cli"
    cli("correlate", reference, deformed, "--out", out, *flags)
    columns = dicstream.read_csv_columns(out / "field_0001.csv")
    frame = json.loads((out / "summary.json").read_text())["frames"][0]
    return columns, frame


@pytest.mark.parametrize("method", ["correli", "icgn1"])
def test_the_field_and_summary_are_the_clis(cli, tmp_path, sample5, method):
    reference, deformed = sample5
    columns, frame = cli_field(cli, tmp_path, reference, deformed, "--method", method, "--threads", 2)
    field = dicstream.correlate(
        dicstream.read_image(reference), dicstream.read_image(deformed), method=method, threads=2
    )
    ny, nx = field["u"].shape
    assert ny * nx == len(columns["x"]) == frame["nodes"]
    for name, decimals in CSV_DECIMALS.items():
        ours = np.round(field[name].ravel(), decimals)
        # The CLI's text is the value rounded; a tie may print either way in the last digit.
        np.testing.assert_allclose(ours, columns[name], rtol=0, atol=1.01 * 10.0**-decimals, err_msg=name)
    assert list(field["status"].ravel()) == list(columns["status"])
    summary = {k: v for k, v in frame.items() if k not in CLI_ONLY}
    assert field["summary"] == summary
    assert field["summary"]["valid"] > 0.9 * field["summary"]["nodes_in_region"]
    # The pair is shifted by (0.1, 0.1) px: the field says so.
    ok = field["status"] == "ok"
    assert abs(np.median(field["u"][ok]) - 0.1) < 0.02
    assert abs(np.median(field["v"][ok]) - 0.1) < 0.02


def test_8_bit_and_float_images_give_the_16_bit_field(sample5):
    reference, deformed = (dicstream.read_image(p) for p in sample5)
    # Sample 5 is 8-bit: the reader kept its levels.
    assert reference.max() <= 255 and deformed.max() <= 255
    expected = dicstream.correlate(reference, deformed, threads=2)
    as_u8 = dicstream.correlate(reference.astype(np.uint8), deformed.astype(np.uint8), threads=2)
    as_float = dicstream.correlate(reference / 65535.0, (deformed / 65535.0).astype(np.float32), threads=2)
    # A view with strides (every column, read backwards twice) is read in its logical order.
    as_view = dicstream.correlate(reference[:, ::-1][:, ::-1], deformed, threads=2)
    for other in (as_u8, as_float, as_view):
        for name in ("u", "v", "exx", "score"):
            np.testing.assert_array_equal(other[name], expected[name], err_msg=name)
        assert other["summary"] == expected["summary"]


def error_of(cli, tmp_path, reference, deformed, *flags):
    """The CLI's error message (its `Error: ` line and causes) for these flags."""
    done = cli("correlate", reference, deformed, "--out", tmp_path / "refused", *flags, check=False)
    assert done.returncode != 0, done.stderr
    return done.stderr


def test_settings_refused_with_the_clis_message(cli, tmp_path, sample5):
    reference, deformed = sample5
    images = [dicstream.read_image(p) for p in sample5]
    for flags, kwargs in [
        (["--zoi", "0"], {"zoi": 0}),
        (["--zoi", "24"], {"zoi": 24}),
        (["--step", "0"], {"step": 0}),
        (["--method", "icgn1", "--zoi", "5"], {"method": "icgn1", "zoi": 5}),
    ]:
        cli_text = error_of(cli, tmp_path, reference, deformed, *flags)
        with pytest.raises(ValueError) as raised:
            dicstream.correlate(*images, **kwargs)
        ours = str(raised.value)
        assert ours.startswith("settings refused for the 512x512 px reference: ")
        cause = ours.split("reference: ", 1)[1]
        assert cause in cli_text, (flags, ours, cli_text)


def test_a_named_choice_is_refused_with_the_clis_words(cli, tmp_path, sample5):
    cli_text = error_of(cli, tmp_path, *sample5, "--method", "icgn3")
    with pytest.raises(ValueError) as raised:
        dicstream.correlate(*[dicstream.read_image(p) for p in sample5], method="icgn3")
    words = str(raised.value).split("method: ", 1)[1]
    assert words == 'method "icgn3": expected correli, icgn1, icgn2 or icgn'
    assert words in cli_text


def test_bad_images_are_refused():
    image = np.zeros((64, 64), dtype=np.uint16)
    cases = [
        ((image, np.zeros((64, 48), dtype=np.uint16)), "deformed image is 48x64 px, expected 64x64 px like the reference"),
        ((image.astype(np.int32), image), "reference image: dtype int32 is not an image"),
        ((image, np.zeros((2, 64, 64), dtype=np.uint16)), "deformed image: a 2-D array (height, width) is needed, not 3-D"),
        ((image, np.full((64, 64), np.nan)), "deformed image: pixel (x 0, y 0) is NaN"),
        ((image, np.full((64, 64), 2.0)), "deformed image: pixel (x 0, y 0) is 2"),
    ]
    for images, message in cases:
        with pytest.raises(ValueError, match=re.escape(message)):
            dicstream.correlate(*images)


def test_image_files_are_read_by_the_clis_reader(tmp_path):
    missing = tmp_path / "missing.tif"
    with pytest.raises(ValueError, match=re.escape(str(missing))):
        dicstream.read_image(missing)
