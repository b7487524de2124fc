"""The napari dock widget, headless (Qt offscreen): a nucleus painted on
every 5th slice is interpolated to Dice > 0.95 against the truth, the
painted slices stay as painted, the next slice worth painting is shown, the
uncertainty layer marks where it is wrong, and the metrics table is filled."""

import numpy as np
import pytest

napari = pytest.importorskip("napari")

import interslice  # noqa: E402
from interslice._napari import InterpolateWidget, phantom_cell  # noqa: E402


def dice(a, b):
    a, b = a != 0, b != 0
    return 2 * np.count_nonzero(a & b) / (np.count_nonzero(a) + np.count_nonzero(b))


def test_widget_interpolates_painted_slices(make_napari_viewer):
    viewer = make_napari_viewer()
    layers = phantom_cell()
    (image, image_kw, _), (truth_all, truth_kw, _) = layers
    viewer.add_image(image, **image_kw)
    truth = (truth_all >= 2).astype(np.uint8)  # the nucleus with its nucleoli, [z, y, x]
    viewer.add_labels(truth, name="nucleus truth", scale=truth_kw["scale"])
    painted = viewer.add_labels(np.zeros_like(truth), name="tracing", scale=truth_kw["scale"])
    # Paint every 5th z slice through the layer, as a brush does.
    zs = [z for z in range(0, truth.shape[0], 5) if truth[z].any()]
    for z in zs:
        idx = np.nonzero(truth[z])
        painted.data_setitem((np.full(idx[0].shape, z), *idx), 1)
    before = np.array(painted.data, copy=True)
    assert viewer.dims.not_displayed == (0,)  # viewing z slices

    widget = InterpolateWidget(viewer)
    viewer.window.add_dock_widget(widget)
    widget.labels_combo.value = painted
    widget.interpolate()
    assert "interpolated" in widget.status_label.value, widget.status_label.value

    got = np.asarray(painted.data)
    assert dice(got, truth) > 0.95, dice(got, truth)
    np.testing.assert_array_equal(got[zs], before[zs])

    # The next slice worth painting is shown, and the button goes there.
    assert "next slice to paint" in widget.suggestion_label.value, widget.suggestion_label.value
    suggested = int(widget.suggestion_label.value.split(":")[1].split()[0])
    assert suggested not in zs and zs[0] < suggested < zs[-1]
    widget._go_to_suggestion()
    assert viewer.dims.current_step[0] == suggested

    # A slice painted after the first run counts as painted too.
    z = zs[2] + 2
    got[z] = 0
    got[z][truth[z] != 0] = 1
    widget.interpolate()
    np.testing.assert_array_equal(np.asarray(painted.data)[z], truth[z])
    np.testing.assert_array_equal(np.asarray(painted.data)[zs], before[zs])

    # With uncertainty shown, a red layer marks where the interpolation may
    # be wrong: nothing on painted slices, and far more where it is wrong.
    widget.uncertainty_check.value = True
    widget.interpolate()
    assert [layer.name for layer in viewer.layers].count("tracing uncertainty") == 1
    unsure = np.asarray(viewer.layers["tracing uncertainty"].data)
    assert unsure.shape == truth.shape
    assert np.all(unsure[zs] == 0) and np.all(unsure[z] == 0)
    assert 0.25 < unsure.max() <= 0.5
    wrong = (np.asarray(painted.data) != 0) != (truth != 0)
    assert wrong.any()
    assert unsure[wrong].mean() > 20 * unsure[~wrong].mean(), (unsure[wrong].mean(), unsure[~wrong].mean())
    # Interpolating again updates the layer instead of adding another.
    widget.interpolate()
    assert [layer.name for layer in viewer.layers].count("tracing uncertainty") == 1

    widget.gt_combo.value = viewer.layers["nucleus truth"]
    widget.seg_combo.value = painted
    widget.evaluate()
    m = widget.last_metrics["labels"]["1"]
    assert m["dice"] > 0.95
    table = widget.metrics_table.value
    assert list(table["columns"]) == ["label 1"]
    assert float(table["data"][table["index"].index("Dice")][0]) > 0.95


def test_sample_data_is_the_phantom_cell():
    (image, _, kind_i), (labels, kw, kind_l) = phantom_cell()
    assert (kind_i, kind_l) == ("image", "labels")
    assert image.shape == labels.shape == (128, 128, 128)
    assert set(np.unique(labels)) >= {0, 1, 2}
    assert kw["scale"] == pytest.approx((0.35, 0.35, 0.35))
    _, want, _ = interslice.phantom(size=128, seed=1)
    np.testing.assert_array_equal(labels, want.T)


def test_manifest_declares_the_widget_and_sample():
    from importlib.resources import files

    import yaml

    m = yaml.safe_load(files("interslice").joinpath("napari.yaml").read_text())
    assert m["name"] == "interslice"
    assert [w["command"] for w in m["contributions"]["widgets"]] == ["interslice.slices_widget"]
    assert [s["key"] for s in m["contributions"]["sample_data"]] == ["phantom_cell"]
