//! `interslice interpolate --image` and `--confidence` through the binary:
//! the image-guided method is the default with an image, drawn slices are
//! kept, the confidence volume is written on the same grid, and an image off
//! the tracing's grid or an image method without an image is a one-line error.
use crate::common::{assert_one_line_error, bin};
use interslice_core::{AnyVolume, Axis, Geometry, LabelVolume, LengthUnit, Volume};

/// A ball (label 1) and an image that shows it (bright inside).
fn case() -> (LabelVolume, Volume<f32>) {
    let g = Geometry::new([24, 22, 20], [0.5, 0.5, 1.0], LengthUnit::Micrometre).unwrap();
    let mut l: LabelVolume = Volume::zeros(g.clone());
    let mut img: Volume<f32> = Volume::zeros(g);
    for k in 0..20 {
        for j in 0..22 {
            for i in 0..24 {
                let (x, y, z) = (i as f64 - 11.5, j as f64 - 10.5, (k as f64 - 9.5) * 2.0);
                let inside = x * x + y * y + z * z < 81.0;
                l.set(i, j, k, u16::from(inside));
                img.set(
                    i,
                    j,
                    k,
                    if inside { 90.0 } else { 30.0 } + ((i * 7 + j * 13 + k * 5) % 11) as f32,
                );
            }
        }
    }
    (l, img)
}

#[test]
fn image_guided_is_the_default_with_an_image_and_writes_the_confidence() {
    let dir = tempfile::tempdir().unwrap();
    let (full, img) = case();
    let drawn = [2usize, 6, 10, 14, 17];
    let mut sparse: LabelVolume = Volume::zeros(full.geometry().clone());
    for &d in &drawn {
        sparse
            .set_slice(Axis::Z, d, &full.slice(Axis::Z, d).unwrap())
            .unwrap();
    }
    let (sp, ip, out, conf) = (
        dir.path().join("sparse.nii.gz"),
        dir.path().join("image.nrrd"),
        dir.path().join("out.nii.gz"),
        dir.path().join("conf.nii.gz"),
    );
    interslice_io::write_volume(&sp, &AnyVolume::U16(sparse.clone())).unwrap();
    interslice_io::write_volume(&ip, &AnyVolume::F32(img)).unwrap();
    let o = bin()
        .arg("interpolate")
        .arg(&sp)
        .args(["--image"])
        .arg(&ip)
        .arg("--out")
        .arg(&out)
        .arg("--confidence")
        .arg(&conf)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).starts_with("image-guided"));
    let result = interslice_io::read_labels(&out).unwrap();
    for &d in &drawn {
        assert_eq!(
            result.slice(Axis::Z, d).unwrap(),
            sparse.slice(Axis::Z, d).unwrap()
        );
    }
    let AnyVolume::F32(c) = interslice_io::read_volume(&conf).unwrap() else {
        panic!("confidence is f32");
    };
    assert!(c.geometry().same_grid(full.geometry()));
    assert!(c.data().iter().all(|&x| (0.5..=1.0).contains(&x)));
    // The ball shows on drawn slices 6 and 10 only, and the image pins its
    // boundary between them (each predicted from the other, the fusion
    // mends the copy): the result is the ball there, and it is sure of it.
    // (Read as it is, this clean image lets the fusion predict each drawn
    // slice exactly, so the calibrated confidence may be sure up to the
    // outline; it is never below the coin toss.)
    for k in 7..10 {
        assert_eq!(
            result.slice(Axis::Z, k).unwrap(),
            full.slice(Axis::Z, k).unwrap(),
            "slice {k}"
        );
        assert!(c.get(11, 10, k) > 0.99, "slice {k}: {}", c.get(11, 10, k));
    }
}

#[test]
fn an_image_off_the_grid_or_an_image_method_without_an_image_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let (full, _) = case();
    let sp = dir.path().join("sparse.nii.gz");
    interslice_io::write_volume(&sp, &AnyVolume::U16(full)).unwrap();
    let g = Geometry::new([10, 10, 10], [1.0; 3], LengthUnit::Micrometre).unwrap();
    let ip = dir.path().join("small.nrrd");
    interslice_io::write_volume(&ip, &AnyVolume::U8(Volume::zeros(g))).unwrap();
    let out = dir.path().join("out.nii.gz");
    let o = bin()
        .arg("interpolate")
        .arg(&sp)
        .arg("--image")
        .arg(&ip)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_one_line_error(&o, "grid");
    assert!(!out.exists());
    let o = bin()
        .arg("interpolate")
        .arg(&sp)
        .args(["--method", "image-guided", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_one_line_error(&o, "--image");
}
