//! The components of a segmentation: the named structures a label volume's
//! values stand for ("Cell" = 1, "Nucleus" = 2, … in cell CT; "Tumour",
//! "Oedema" in a brain MRI project), each with a display colour.
//!
//! One definition shared by the project file, the server's labels, the
//! exported 3D Slicer `.seg.nrrd` segment table and ITK-SNAP label
//! descriptions, and `--label NAME` on the command line.
use std::fmt;

/// Longest component name, in characters (the store and the formats agree).
pub const MAX_NAME_CHARS: usize = 64;
/// Most components one project or file may declare.
pub const MAX_COMPONENTS: usize = 1024;

/// One component: the voxel value that marks it, its name and its colour.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Component {
    /// The label value (1..=65535; 0 is background).
    pub value: u16,
    /// The name shown to people (1..=64 characters, no control characters).
    pub name: String,
    /// sRGB colour.
    pub color: [u8; 3],
}

/// Why a component list or a component reference is not valid.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ComponentError {
    /// A name that is empty, too long or holds control characters.
    #[error("component name '{0}' is not valid (1 to 64 characters, no control characters)")]
    BadName(String),
    /// Two components with one name or one value.
    #[error("component {0} is declared twice")]
    Duplicate(String),
    /// Value 0, or more values than a label volume holds.
    #[error("component value {0} is not valid (1..=65535)")]
    BadValue(u32),
    /// More than [`MAX_COMPONENTS`].
    #[error("too many components ({0}; at most {MAX_COMPONENTS})")]
    TooMany(usize),
    /// A colour that is not `#rrggbb`.
    #[error("colour '{0}' is not #rrggbb")]
    BadColor(String),
    /// `--label NAME` naming no component.
    #[error("no component named '{name}' ({known})")]
    Unknown {
        /// The name asked for.
        name: String,
        /// What is known, for the message.
        known: String,
    },
}

/// Colours given to components in order, when none is chosen (the first four
/// are the cell-CT set's; distinct on a dark background).
pub const PALETTE: [[u8; 3]; 12] = [
    [0xe6, 0x19, 0x4b],
    [0x3c, 0xb4, 0x4b],
    [0x43, 0x63, 0xd8],
    [0xf5, 0x82, 0x31],
    [0x91, 0x1e, 0xb4],
    [0x42, 0xd4, 0xf4],
    [0xf0, 0x32, 0xe6],
    [0xbf, 0xef, 0x45],
    [0xfa, 0xbe, 0xd4],
    [0x46, 0x99, 0x90],
    [0xdc, 0xbe, 0xff],
    [0x9a, 0x63, 0x24],
];

impl Component {
    /// A component with the palette colour of its value.
    pub fn new(value: u16, name: impl Into<String>) -> Component {
        Component {
            value,
            name: name.into(),
            color: PALETTE[(usize::from(value).max(1) - 1) % PALETTE.len()],
        }
    }

    /// The colour as `#rrggbb`.
    pub fn hex_color(&self) -> String {
        to_hex_color(self.color)
    }
}

/// An sRGB colour as `#rrggbb` (lower case).
pub fn to_hex_color([r, g, b]: [u8; 3]) -> String {
    format!("#{r:02x}{g:02x}{b:02x}")
}

/// Parse `#rrggbb` (case-insensitive).
pub fn parse_hex_color(s: &str) -> Result<[u8; 3], ComponentError> {
    let bad = || ComponentError::BadColor(s.chars().take(16).collect());
    let hex = s.strip_prefix('#').ok_or_else(bad)?;
    if hex.len() != 6 || !hex.chars().all(|c| c.is_ascii_hexdigit()) {
        return Err(bad());
    }
    let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).map_err(|_| bad());
    Ok([byte(0)?, byte(2)?, byte(4)?])
}

/// An ordered list of components with distinct names and values.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Components(Vec<Component>);

impl Components {
    /// Check and wrap a list: names valid and distinct (case-insensitively),
    /// values distinct and non-zero, at most [`MAX_COMPONENTS`].
    pub fn new(list: Vec<Component>) -> Result<Components, ComponentError> {
        if list.len() > MAX_COMPONENTS {
            return Err(ComponentError::TooMany(list.len()));
        }
        for (n, c) in list.iter().enumerate() {
            check_name(&c.name)?;
            if c.value == 0 {
                return Err(ComponentError::BadValue(0));
            }
            for d in &list[..n] {
                if d.value == c.value {
                    return Err(ComponentError::Duplicate(format!("value {}", c.value)));
                }
                if d.name.eq_ignore_ascii_case(&c.name) {
                    return Err(ComponentError::Duplicate(format!("'{}'", c.name)));
                }
            }
        }
        Ok(Components(list))
    }

    /// The cell-CT set of the original study and of the demo: Cell 1,
    /// Nucleus 2, Nucleolus 1 = 3, Nucleolus 2 = 4.
    pub fn cell_ct() -> Components {
        Components(
            ["Cell", "Nucleus", "Nucleolus 1", "Nucleolus 2"]
                .iter()
                .zip(1u16..)
                .map(|(n, v)| Component::new(v, *n))
                .collect(),
        )
    }

    /// Components from a comma-separated list of names ("Tumour,Oedema"),
    /// valued 1, 2, … in order, with palette colours.
    pub fn from_names(list: &str) -> Result<Components, ComponentError> {
        let names: Vec<&str> = list.split(',').map(str::trim).collect();
        if names.len() > MAX_COMPONENTS {
            return Err(ComponentError::TooMany(names.len()));
        }
        Components::new(
            names
                .into_iter()
                .zip(1u16..)
                .map(|(n, v)| Component::new(v, n))
                .collect(),
        )
    }

    /// The components, in order.
    pub fn as_slice(&self) -> &[Component] {
        &self.0
    }

    /// The component with this value.
    pub fn by_value(&self, value: u16) -> Option<&Component> {
        self.0.iter().find(|c| c.value == value)
    }

    /// The component with this name (case-insensitive).
    pub fn by_name(&self, name: &str) -> Option<&Component> {
        self.0
            .iter()
            .find(|c| c.name.eq_ignore_ascii_case(name.trim()))
    }

    /// A label given on a command line or in a request: a number (any label
    /// value, named or not) or a component's name.
    pub fn resolve(&self, label: &str) -> Result<u16, ComponentError> {
        if let Ok(v) = label.trim().parse::<u16>() {
            return Ok(v);
        }
        self.by_name(label)
            .map(|c| c.value)
            .ok_or_else(|| ComponentError::Unknown {
                name: label.chars().take(MAX_NAME_CHARS).collect(),
                known: if self.0.is_empty() {
                    "no component names are known here; give the label's number".into()
                } else {
                    let names: Vec<String> = self
                        .0
                        .iter()
                        .map(|c| format!("{} = {}", c.name, c.value))
                        .collect();
                    format!("known: {}", names.join(", "))
                },
            })
    }

    /// Whether no component is declared.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl fmt::Display for Components {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (n, c) in self.0.iter().enumerate() {
            if n > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{} = {}", c.name, c.value)?;
        }
        Ok(())
    }
}

fn check_name(name: &str) -> Result<(), ComponentError> {
    let n = name.chars().count();
    if name.trim() != name || n == 0 || n > MAX_NAME_CHARS || name.chars().any(char::is_control) {
        return Err(ComponentError::BadName(name.chars().take(80).collect()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_resolve_case_insensitively_and_numbers_pass_through() {
        let c = Components::from_names("Tumour, Oedema").unwrap();
        assert_eq!(c.resolve("tumour").unwrap(), 1);
        assert_eq!(c.resolve("Oedema").unwrap(), 2);
        assert_eq!(c.resolve("7").unwrap(), 7);
        let e = c.resolve("Necrosis").unwrap_err().to_string();
        assert_eq!(
            e,
            "no component named 'Necrosis' (known: Tumour = 1, Oedema = 2)"
        );
        assert!(
            Components::default()
                .resolve("Nucleus")
                .unwrap_err()
                .to_string()
                .contains("give the label's number")
        );
    }

    #[test]
    fn cell_ct_set_keeps_the_study_values_and_colours() {
        let c = Components::cell_ct();
        assert_eq!(c.resolve("Nucleolus 2").unwrap(), 4);
        assert_eq!(c.by_value(1).unwrap().hex_color(), "#e6194b");
        assert_eq!(c.by_value(2).unwrap().hex_color(), "#3cb44b");
    }

    #[test]
    fn bad_lists_are_refused() {
        assert!(matches!(
            Components::from_names("A,a"),
            Err(ComponentError::Duplicate(_))
        ));
        assert!(matches!(
            Components::from_names("A,,B"),
            Err(ComponentError::BadName(_))
        ));
        let long = "x".repeat(65);
        assert!(Components::from_names(&long).is_err());
        assert!(Components::new(vec![Component::new(0, "Zero")]).is_err());
    }

    #[test]
    fn hex_colours_round_trip() {
        assert_eq!(parse_hex_color("#FF8000").unwrap(), [255, 128, 0]);
        assert_eq!(Component::new(3, "x").hex_color(), "#4363d8");
        assert!(parse_hex_color("ff8000").is_err());
        assert!(parse_hex_color("#ff80").is_err());
        assert!(parse_hex_color("#ggg000").is_err());
    }
}
