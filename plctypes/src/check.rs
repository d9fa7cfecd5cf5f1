//! A user's declarations held against the image: every member where
//! TwinCAT places it, beside where the model puts it.
//!
//! Members are matched by name (case-insensitively, as ST names are), then
//! what is left in order, so a member named otherwise is still checked and a
//! missing one does not shift the blame onto every member after it.

use std::collections::BTreeSet;
use std::fmt;

use crate::error::{DeclarationError, Place};
use crate::packing::{Declarations, Laid, Placed};
use crate::parse::{Body, TypeExpr};
use crate::types::{DataType, ImageTypes, StructType, INPUTS, OUTPUTS};

/// One way a declaration differs from the image.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Difference {
    Offset {
        expected: usize,
        actual: usize,
    },
    Size {
        expected: usize,
        actual: usize,
    },
    Bit {
        expected: u8,
        actual: Option<u8>,
    },
    /// An array that does not start at 0 (000 §6 indexes slots from 0).
    LowBound {
        low: i64,
        expected_high: i64,
    },
    TooShort {
        count: usize,
        expected: usize,
    },
    Overrun {
        count: usize,
        expected: usize,
    },
    Missing {
        member: String,
        offset: usize,
    },
    Extra,
    /// `unpacked`: the structure has no `pack_mode`, the likeliest cause.
    StructSize {
        expected: usize,
        actual: usize,
        unpacked: bool,
    },
}

impl fmt::Display for Difference {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Difference::Offset { expected, actual } => {
                write!(f, "at byte {actual}; the image has it at byte {expected}")
            }
            Difference::Size { expected, actual } => {
                write!(f, "{actual} bytes; the image's is {expected} bytes")
            }
            Difference::Bit { expected, actual } => match actual {
                Some(actual) => write!(f, "bit {actual}; the image's is bit {expected}"),
                None => write!(f, "a whole member; the image's is bit {expected} of its byte"),
            },
            Difference::LowBound { low, expected_high } => write!(
                f,
                "counts from {low}; the image's slots are [0..{expected_high}] (000 §6 reads Inputs.RxMessage[i] and writes Outputs.TxMessage[i] from i = 0)"
            ),
            Difference::TooShort { count, expected } => write!(
                f,
                "{count} elements; the image has {expected}: the last {} are not declared",
                expected - count
            ),
            Difference::Overrun { count, expected } => write!(
                f,
                "{count} elements; the image has {expected}: the {} beyond it overrun the image",
                count - expected
            ),
            Difference::Missing { member, offset } => {
                write!(f, "no member for the image's {member} (byte {offset})")
            }
            Difference::Extra => write!(f, "not in the image"),
            Difference::StructSize {
                expected,
                actual,
                unpacked,
            } => {
                write!(f, "{actual} bytes in all; the image's is {expected} bytes")?;
                if *unpacked {
                    write!(f, " (the TYPE has no {{attribute 'pack_mode' := '0'}}, so TwinCAT aligns its members: 000 §6)")?;
                }
                Ok(())
            }
        }
    }
}

/// A difference, where the user declared it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Defect {
    pub place: Place,
    /// The user's `Type.member`.
    pub member: String,
    /// The image's member it stands for.
    pub image_member: String,
    pub difference: Difference,
}

impl fmt::Display for Defect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.place, self.member)?;
        if !self.image_member.is_empty() {
            write!(f, " (the image's {})", self.image_member)?;
        }
        write!(f, ": {}", self.difference)
    }
}

/// What a check looked at and found.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Checked {
    /// The user's structures that stand for the image's, by image name.
    pub matched: Vec<(String, String)>,
    /// Image structures no declaration stands for.
    pub unmatched: Vec<String>,
    pub members_checked: usize,
    pub defects: Vec<Defect>,
}

/// Which user structures are the images: named, or the one with a
/// `NoOfTxMessages` (outputs) or `NoOfRxMessages` (inputs) member.
#[derive(Debug, Clone, Default)]
pub struct Roots {
    pub outputs: Option<String>,
    pub inputs: Option<String>,
}

/// Holds the user's `declarations` against `image`.
pub fn check(
    declarations: &Declarations,
    image: &ImageTypes,
    roots: &Roots,
) -> Result<Checked, DeclarationError> {
    let mut checker = Checker {
        declarations,
        image,
        seen: BTreeSet::new(),
        out: Checked::default(),
    };
    for (root, named, marker) in [
        (OUTPUTS, &roots.outputs, "NoOfTxMessages"),
        (INPUTS, &roots.inputs, "NoOfRxMessages"),
    ] {
        let user = match named {
            Some(name) => Some(name.clone()),
            None => declarations
                .types()
                .iter()
                .find(|t| {
                    matches!(&t.body, Body::Struct(m) if m.iter().any(|m| m.name.eq_ignore_ascii_case(marker)))
                })
                .map(|t| t.name.clone()),
        };
        let expected = image.structure(root).expect("the image declares both");
        match user {
            Some(user) => checker.structure(expected, &user, image_name(root))?,
            None => checker.out.unmatched.push(root.to_string()),
        }
    }
    let mut out = checker.out;
    out.defects
        .sort_by(|a, b| (&a.place.file, a.place.line).cmp(&(&b.place.file, b.place.line)));
    Ok(out)
}

/// The manual's name of an image (000 §6: `Outputs.TxCounter`, `Inputs.RxMessage[i]`).
fn image_name(root: &str) -> &'static str {
    match root {
        OUTPUTS => "Outputs",
        _ => "Inputs",
    }
}

struct Checker<'a> {
    declarations: &'a Declarations,
    image: &'a ImageTypes,
    /// (image type, user type) pairs already held against each other.
    seen: BTreeSet<(String, String)>,
    out: Checked,
}

impl Checker<'_> {
    fn structure(
        &mut self,
        expected: &StructType,
        user: &str,
        image_path: &str,
    ) -> Result<(), DeclarationError> {
        if !self
            .seen
            .insert((expected.name.clone(), user.to_ascii_lowercase()))
        {
            return Ok(());
        }
        let Some(laid) = self.declarations.lay_out(user)? else {
            return Ok(());
        };
        self.out
            .matched
            .push((expected.name.clone(), laid.name.clone()));
        let pairs = pair(expected, &laid);
        for (image_member, placed) in pairs {
            match (image_member, placed) {
                (Some(m), Some(p)) => self.member(&laid, m, p, image_path)?,
                (Some(m), None) => self.defect(
                    &laid.place,
                    laid.name.clone(),
                    format!("{image_path}.{}", m.name),
                    Difference::Missing {
                        member: m.name.clone(),
                        offset: m.offset,
                    },
                ),
                (None, Some(p)) => self.defect(
                    &Place {
                        line: p.line,
                        ..laid.place.clone()
                    },
                    format!("{}.{}", laid.name, p.name),
                    String::new(),
                    Difference::Extra,
                ),
                (None, None) => {}
            }
        }
        if laid.size != expected.size {
            self.defect(
                &laid.place,
                laid.name.clone(),
                image_path.to_string(),
                Difference::StructSize {
                    expected: expected.size,
                    actual: laid.size,
                    unpacked: laid.pack_mode.is_none_or(|mode| mode > 1),
                },
            );
        }
        Ok(())
    }

    fn member(
        &mut self,
        laid: &Laid,
        expected: &crate::types::Member,
        placed: &Placed,
        image_path: &str,
    ) -> Result<(), DeclarationError> {
        self.out.members_checked += 1;
        let place = Place {
            line: placed.line,
            ..laid.place.clone()
        };
        let user_path = format!("{}.{}", laid.name, placed.name);
        let image_path = format!("{image_path}.{}", expected.name);
        if placed.offset != expected.offset {
            self.defect(
                &place,
                user_path.clone(),
                image_path.clone(),
                Difference::Offset {
                    expected: expected.offset,
                    actual: placed.offset,
                },
            );
        }
        if let Some(bit) = expected.bit {
            if placed.bit != Some(bit) {
                self.defect(
                    &place,
                    user_path,
                    image_path,
                    Difference::Bit {
                        expected: bit,
                        actual: placed.bit,
                    },
                );
            }
            return Ok(());
        }
        let expected_type = self.image.resolve(&expected.data_type);
        self.data_type(
            &expected_type,
            &placed.data_type,
            &place,
            &user_path,
            &image_path,
        )
    }

    fn data_type(
        &mut self,
        expected: &DataType,
        actual: &TypeExpr,
        place: &Place,
        user_path: &str,
        image_path: &str,
    ) -> Result<(), DeclarationError> {
        match (expected, actual) {
            (
                DataType::Array {
                    low: e_low,
                    high: e_high,
                    element: e_element,
                },
                TypeExpr::Array { low, high, element },
            ) => {
                let expected_count = crate::types::element_count(*e_low, *e_high);
                let count = crate::types::element_count(*low, *high);
                if low != e_low {
                    self.defect(
                        place,
                        user_path.into(),
                        image_path.into(),
                        Difference::LowBound {
                            low: *low,
                            expected_high: *e_high,
                        },
                    );
                }
                if count < expected_count {
                    self.defect(
                        place,
                        user_path.into(),
                        image_path.into(),
                        Difference::TooShort {
                            count,
                            expected: expected_count,
                        },
                    );
                } else if count > expected_count {
                    self.defect(
                        place,
                        user_path.into(),
                        image_path.into(),
                        Difference::Overrun {
                            count,
                            expected: expected_count,
                        },
                    );
                }
                let element = self.declarations.resolve(element, place)?;
                self.data_type(
                    &self.image.resolve(e_element),
                    &element,
                    place,
                    &format!("{user_path}[]"),
                    &format!("{image_path}[]"),
                )
            }
            (DataType::Named(e_name), TypeExpr::Named(name))
                if self.declarations.lay_out(name)?.is_some() =>
            {
                let image = self.image;
                match image.structure(e_name) {
                    Some(expected) => self.structure(expected, name, image_path),
                    None => Ok(()),
                }
            }
            _ => {
                let expected_size = self.image.size_of(expected);
                let actual_size = self.declarations.size_of(actual, place)?;
                if expected_size != actual_size {
                    self.defect(
                        place,
                        user_path.into(),
                        image_path.into(),
                        Difference::Size {
                            expected: expected_size,
                            actual: actual_size,
                        },
                    );
                }
                Ok(())
            }
        }
    }

    fn defect(
        &mut self,
        place: &Place,
        member: String,
        image_member: String,
        difference: Difference,
    ) {
        self.out.defects.push(Defect {
            place: place.clone(),
            member,
            image_member,
            difference,
        });
    }
}

type Pair<'a> = (Option<&'a crate::types::Member>, Option<&'a Placed>);

/// The image's members beside the user's: same names first, then the rest in order.
fn pair<'a>(expected: &'a StructType, laid: &'a Laid) -> Vec<Pair<'a>> {
    let mut used = vec![false; laid.members.len()];
    let mut pairs: Vec<Pair<'a>> = expected
        .members
        .iter()
        .map(|m| {
            let found = laid
                .members
                .iter()
                .position(|p| p.name.eq_ignore_ascii_case(&m.name));
            if let Some(i) = found {
                used[i] = true;
            }
            (Some(m), found.map(|i| &laid.members[i]))
        })
        .collect();
    let mut rest = laid
        .members
        .iter()
        .enumerate()
        .filter(|(i, _)| !used[*i])
        .map(|(_, p)| p);
    for pair in pairs.iter_mut().filter(|p| p.1.is_none()) {
        pair.1 = rest.next();
    }
    pairs.extend(rest.map(|p| (None, Some(p))));
    pairs
}
