"""The napari plugin: a dock widget that interpolates the slices painted in
a Labels layer along the axis being viewed and evaluates one Labels layer
against another, and the phantom cell as sample data.

napari holds arrays in its own axis order (a z-stack is ``[z, y, x]``, the
slider on axis 0); interslice works on ``[x, y, z]``. The widget passes
``data.T`` (a view) and the layer's scale reversed, so nothing is copied for
a C-ordered layer and the viewed axis maps to ``ndim - 1 - axis``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from magicgui.widgets import CheckBox, ComboBox, Container, Label, PushButton, Table

import interslice

#: Rows of the metrics table: (shown name, key of ``interslice.evaluate``).
METRIC_ROWS = [
    ("Dice", "dice"),
    ("Jaccard", "jaccard"),
    ("sensitivity", "sensitivity"),
    ("specificity", "specificity"),
    ("precision", "precision"),
    ("volume similarity", "volume_similarity"),
    ("volume GT", "volume_gt"),
    ("volume seg", "volume_seg"),
    ("HD", "hd"),
    ("HD95", "hd95"),
    ("ASSD", "assd"),
    ("MASD", "masd"),
    ("NSD", "nsd"),
]

#: Every label a Labels layer can hold (interslice's own bound is for files
#: and arrays that may be intensities read as labels).
ALL_LABELS = 65535


def phantom_cell():
    """Sample data: the 128³ phantom cell (0.35 µm voxels) and its exact
    labels (1 cell, 2 nucleus, 3.. nucleoli), as napari ``[z, y, x]`` layers."""
    image, labels, meta = interslice.phantom(size=128, seed=1)
    scale = tuple(reversed(meta["spacing"]))
    return [
        (image.T, {"name": "phantom cell", "scale": scale}, "image"),
        (labels.T, {"name": "phantom truth", "scale": scale}, "labels"),
    ]


@dataclass
class _Painted:
    """What the widget knows of a Labels layer after it interpolated it."""

    axis: int
    drawn: set[int]
    result: np.ndarray


def _fmt(x) -> str:
    if x is None:
        return "-"
    if isinstance(x, int) or float(x).is_integer():
        return str(int(x))
    return f"{x:.4g}"


def _slices_along(axis: int, indices, ndim: int = 3):
    idx = [slice(None)] * ndim
    idx[axis] = list(indices)
    return tuple(idx)


class InterpolateWidget(Container):
    """Interpolate the painted slices of a Labels layer; evaluate labels.

    Paint a structure on a few slices of a Labels layer while viewing one
    axis, press *Interpolate painted slices*: the slices in between are
    filled by interslice (every label on its own), the painted slices are
    left as they are. Paint more slices (or correct an interpolated one)
    and press again: every slice you changed counts as painted. With *show
    uncertainty*, an Image layer "<labels> uncertainty" tints, in red over
    the image, where the method is least sure of the label it gave
    (``1 - confidence``: 0 where it is sure, 0.5 where it guesses), the
    places worth checking or painting. *Evaluate* measures a segmentation
    layer against a ground-truth layer.
    """

    def __init__(self, napari_viewer):
        self._viewer = napari_viewer
        self._state: dict[int, _Painted] = {}
        self.last_metrics: dict | None = None
        method_choices = [(f"default ({interslice.DEFAULT_METHOD})", None)] + [
            (m["name"], m["name"]) for m in interslice.methods()
        ]
        self.labels_combo = ComboBox(label="labels", choices=self._labels_layers)
        self.image_combo = ComboBox(label="image", choices=self._image_layers, nullable=True, value=None)
        self.method_combo = ComboBox(label="method", choices=method_choices, value=None)
        # Off by default: the confidence costs a second pass per label.
        self.uncertainty_check = CheckBox(text="show uncertainty", value=False)
        self.run_button = PushButton(text="Interpolate painted slices")
        self.status_label = Label(value="")
        self.suggestion_label = Label(value="")
        self.goto_button = PushButton(text="Go to suggested slice", visible=False)
        self.gt_combo = ComboBox(label="ground truth", choices=self._labels_layers)
        self.seg_combo = ComboBox(label="segmentation", choices=self._labels_layers)
        self.evaluate_button = PushButton(text="Evaluate")
        self.metrics_table = Table(value={"data": [], "index": [], "columns": []})
        self._suggested: tuple[int, int] | None = None
        super().__init__(
            widgets=[
                self.labels_combo,
                self.image_combo,
                self.method_combo,
                self.uncertainty_check,
                self.run_button,
                self.status_label,
                self.suggestion_label,
                self.goto_button,
                self.gt_combo,
                self.seg_combo,
                self.evaluate_button,
                self.metrics_table,
            ]
        )
        self.run_button.changed.connect(self.interpolate)
        self.evaluate_button.changed.connect(self.evaluate)
        self.goto_button.changed.connect(self._go_to_suggestion)
        events = napari_viewer.layers.events
        for ev in (events.inserted, events.removed, events.reordered):
            ev.connect(self.reset_choices)

    # -- layer choices -------------------------------------------------------
    def _layers(self, kind):
        return [(layer.name, layer) for layer in self._viewer.layers if isinstance(layer, kind)]

    def _labels_layers(self, _widget=None):
        from napari.layers import Labels

        return self._layers(Labels)

    def _image_layers(self, _widget=None):
        from napari.layers import Image

        return self._layers(Image)

    def _say(self, text: str) -> None:
        self.status_label.value = text

    # -- interpolation -------------------------------------------------------
    def viewed_axis(self, layer) -> int:
        """The axis of `layer` the viewer slices along (the slider of a 2D view)."""
        dims = self._viewer.dims
        offset = dims.ndim - layer.ndim
        axes = [d - offset for d in dims.not_displayed if d - offset >= 0]
        if len(axes) != 1:
            raise interslice.Error("view the labels in 2D, one slice at a time, to interpolate")
        return axes[0]

    def interpolate(self) -> None:
        """Interpolate the chosen Labels layer along the viewed axis."""
        layer = self.labels_combo.value
        if layer is None:
            self._say("choose a Labels layer")
            return
        try:
            self._interpolate(layer)
        except interslice.Error as e:
            self._say(f"error: {e}")

    def _interpolate(self, layer) -> None:
        data = layer.data
        if not isinstance(data, np.ndarray) or data.ndim != 3:
            raise interslice.Error("the Labels layer must be a 3-D numpy array")
        axis = self.viewed_axis(layer)
        n = data.shape[axis]
        other = tuple(a for a in range(3) if a != axis)
        st = self._state.get(id(layer))
        if st is None or st.axis != axis or st.result.shape != data.shape:
            drawn = set(np.flatnonzero(np.any(data != 0, axis=other)).tolist())
        else:
            changed = np.flatnonzero(np.any(data != st.result, axis=other)).tolist()
            drawn = st.drawn | set(changed)
        drawn_list = sorted(drawn)
        if len(drawn_list) < 2:
            raise interslice.Error(f"paint at least two slices along axis {axis} (found {len(drawn_list)})")
        sparse = np.zeros_like(data)
        sparse[_slices_along(axis, drawn_list)] = data[_slices_along(axis, drawn_list)]
        image = self.image_combo.value
        img = None
        if image is not None:
            img = np.asarray(image.data)
            if img.shape != data.shape:
                raise interslice.Error(f"image and labels differ: shape {img.shape} vs {data.shape}")
            img = img.T
        spacing = tuple(float(s) for s in reversed(layer.scale[-3:]))
        result = interslice.interpolate(
            sparse.T,
            drawn=drawn_list,
            axis=2 - axis,
            spacing=spacing,
            image=img,
            method=self.method_combo.value,
            # A Labels layer holds labels, not intensities: every one counts.
            max_labels=ALL_LABELS,
            confidence=self.uncertainty_check.value,
        )
        if self.uncertainty_check.value:
            out, confidence = result[0].T, result[1].T
            self._show_uncertainty(layer, confidence)
        else:
            out = result.T
        undrawn = [i for i in range(n) if i not in drawn]
        if undrawn:
            # Only the slices nobody painted change.
            sel = _slices_along(axis, undrawn)
            data[sel] = out[sel]
        layer.refresh()
        self._state[id(layer)] = _Painted(axis, drawn, np.array(data, copy=True))
        self._say(f"interpolated {len(undrawn)} slices from {len(drawn_list)} painted along axis {axis}")
        self._suggest(layer, sparse, drawn_list, axis, spacing, img)

    def _show_uncertainty(self, layer, confidence: np.ndarray) -> None:
        """Add (or update) the Image layer tinting where `layer`'s
        interpolation is least sure: ``1 - confidence``, red, added over
        what is below it."""
        name = f"{layer.name} uncertainty"
        data = 1.0 - confidence
        if name in self._viewer.layers:
            shown = self._viewer.layers[name]
            shown.data = data
        else:
            self._viewer.add_image(
                data,
                name=name,
                scale=layer.scale,
                translate=layer.translate,
                colormap="red",
                blending="additive",
                contrast_limits=(0.0, 0.5),
            )

    def _suggest(self, layer, sparse, drawn, axis, spacing, img) -> None:
        """Show the next slice worth painting, when interslice can advise."""
        advice = interslice.advise(
            sparse.T, drawn=drawn, axis=2 - axis, spacing=spacing, image=img, count=1, max_labels=ALL_LABELS
        )
        best = advice["suggestions"]
        if not best:
            self.suggestion_label.value = ""
            self.goto_button.visible = False
            return
        index = int(best[0]["slice"])
        self._suggested = (axis + self._viewer.dims.ndim - layer.ndim, index)
        self.suggestion_label.value = (
            f"next slice to paint: {index} (predicted Dice now {advice['predicted_dice']:.3f}, "
            f"+{best[0]['dice_gain']:.4f} with it)"
        )
        self.goto_button.visible = True

    def _go_to_suggestion(self) -> None:
        if self._suggested is not None:
            self._viewer.dims.set_current_step(*self._suggested)

    # -- evaluation ----------------------------------------------------------
    def evaluate(self) -> None:
        """Measure the segmentation layer against the ground-truth layer."""
        gt, seg = self.gt_combo.value, self.seg_combo.value
        if gt is None or seg is None:
            self._say("choose a ground truth and a segmentation Labels layer")
            return
        try:
            g, s = np.asarray(gt.data), np.asarray(seg.data)
            if g.shape != s.shape:
                raise interslice.Error(f"ground truth and segmentation differ: shape {g.shape} vs {s.shape}")
            if g.ndim != 3:
                raise interslice.Error("evaluation needs 3-D Labels layers")
            spacing = tuple(float(x) for x in reversed(gt.scale[-3:]))
            r = interslice.evaluate(g.T, s.T, spacing=spacing)
        except interslice.Error as e:
            self._say(f"error: {e}")
            return
        self.last_metrics = r
        cols = [(f"label {k}", m) for k, m in r["labels"].items()]
        if len(cols) != 1:
            cols.append(("all labels", r["foreground"]))
        self.metrics_table.value = {
            "data": [[_fmt(m[key]) for _, m in cols] for _, key in METRIC_ROWS],
            "index": [name for name, _ in METRIC_ROWS],
            "columns": [name for name, _ in cols],
        }
        n = len(r["labels"])
        self._say(f"{seg.name} against {gt.name}: {n} label{'' if n == 1 else 's'}")
