"""The README's napari screenshot: the phantom cell, its nucleus painted on
every 5th z slice and interpolated by the dock widget with its uncertainty
shown (red), evaluated against the truth. Renders offscreen (napari's `viewer.screenshot`):

    QT_QPA_PLATFORM=offscreen xvfb-run -a python python/examples/napari_screenshot.py docs/screenshots/napari.png
"""

import sys

import napari
import numpy as np
from qtpy.QtWidgets import QApplication

from interslice._napari import InterpolateWidget, phantom_cell


def main(out):
    viewer = napari.Viewer(show=False)
    (image, image_kw, _), (truth_all, kw, _) = phantom_cell()
    viewer.add_image(image, **image_kw)
    truth = (truth_all >= 2).astype(np.uint8)
    viewer.add_labels(truth * 2, name="nucleus truth", scale=kw["scale"], opacity=0.0)
    tracing = viewer.add_labels(np.zeros_like(truth), name="tracing", scale=kw["scale"])
    for z in range(0, truth.shape[0], 5):
        tracing.data[z] = truth[z]
    widget = InterpolateWidget(viewer)
    viewer.window.add_dock_widget(widget, name="Interpolate & evaluate (interslice)", area="right")
    widget.labels_combo.value = tracing
    widget.uncertainty_check.value = True
    widget.interpolate()
    widget.gt_combo.value = viewer.layers["nucleus truth"]
    widget.seg_combo.value = tracing
    viewer.layers["nucleus truth"].data = truth
    widget.evaluate()
    viewer.dims.set_current_step(0, 62)  # an interpolated slice
    viewer.window._qt_window.resize(1500, 950)
    QApplication.processEvents()
    viewer.reset_view()
    viewer.camera.zoom *= 2.0
    QApplication.processEvents()
    viewer.screenshot(out, canvas_only=False, flash=False)
    print("wrote", out, "dice", widget.last_metrics["labels"]["1"]["dice"])


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "napari.png")
