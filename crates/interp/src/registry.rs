//! The list of interpolators, by `--method` name. The default comes first.
use crate::image::ImageGuided;
use crate::image::conditioned::Conditioned;
use crate::{InterpError, Interpolator};

/// The method used when none is named (and no image is given): the
/// leave-one-out choice among the shape methods (see `docs/interpolation.md`).
pub const DEFAULT_METHOD: &str = "shape-auto";

/// The method used when an intensity image is given and no method is named.
pub const IMAGE_METHOD: &str = "image-guided";

/// The method used when none is named: [`IMAGE_METHOD`] with the cell's
/// intensity image, [`DEFAULT_METHOD`] without.
pub fn default_method(with_image: bool) -> &'static str {
    if with_image {
        IMAGE_METHOD
    } else {
        DEFAULT_METHOD
    }
}

/// Every interpolator, the default first.
pub fn methods() -> Vec<Box<dyn Interpolator>> {
    let mut all: Vec<Box<dyn Interpolator>> = vec![
        Box::new(crate::shape_based::ShapeBased),
        Box::new(crate::shape_area::ShapeArea::default()),
        Box::new(crate::shape_cubic::ShapeCubic),
        Box::new(crate::linear::Linear),
        Box::new(crate::aligned::ShapeAligned::default()),
        Box::new(crate::nearest::Nearest),
        Box::new(crate::auto::ShapeAuto::default()),
    ];
    // The four mesh-based methods of the original system.
    all.extend(crate::mesh::mesh_methods());
    if let Some(p) = all.iter().position(|m| m.name() == DEFAULT_METHOD) {
        let d = all.remove(p);
        all.insert(0, d);
    }
    all
}

/// The interpolator named `name`; an unknown name is an error listing the
/// valid ones.
pub fn by_name(name: &str) -> Result<Box<dyn Interpolator>, InterpError> {
    let all = methods();
    let names: Vec<&'static str> = all.iter().map(|m| m.name()).collect();
    all.into_iter().find(|m| m.name() == name).ok_or_else(|| {
        InterpError::Input(format!(
            "unknown method '{name}' (valid: {})",
            names.join(", ")
        ))
    })
}

/// The interpolator named `name` (or the image method, or the default, when
/// `None`), given the intensity volume of the cell when there is one. The
/// image methods need `image`; an unknown name lists the valid ones.
pub fn by_name_with_image(
    name: Option<&str>,
    image: Option<Conditioned>,
) -> Result<Box<dyn Interpolator>, InterpError> {
    match (name.unwrap_or(default_method(image.is_some())), image) {
        (IMAGE_METHOD, Some(img)) => Ok(Box::new(ImageGuided::new(img))),
        (IMAGE_METHOD, None) => Err(InterpError::Input(format!(
            "method {IMAGE_METHOD} needs the intensity volume (--image)"
        ))),
        (name, _) => by_name(name).map_err(|e| match e {
            InterpError::Input(m) => {
                InterpError::Input(format!("{m}, {IMAGE_METHOD} (with an image)"))
            }
            other => other,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_first_and_names_unique() {
        let all = methods();
        assert_eq!(all[0].name(), DEFAULT_METHOD);
        let mut names: Vec<_> = all.iter().map(|m| m.name()).collect();
        names.sort_unstable();
        let n = names.len();
        names.dedup();
        assert_eq!(names.len(), n);
        assert!(all.iter().all(|m| !m.description().is_empty()));
    }

    #[test]
    fn unknown_name_lists_the_valid_ones() {
        let e = by_name("nope").err().expect("unknown method").to_string();
        assert!(
            e.contains("nope") && e.contains("shape-based") && e.contains("linear"),
            "{e}"
        );
        assert_eq!(by_name("linear").unwrap().name(), "linear");
    }
}
