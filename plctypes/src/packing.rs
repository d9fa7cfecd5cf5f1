//! Where TwinCAT places each member of a declared structure.
//!
//! The attribute `pack_mode` (Beckhoff Infosys, "Attribute 'pack_mode'"):
//! 0 and 1 place members without gaps; 2, 4 and 8 align each member to its
//! own size up to that many bytes. A structure without the attribute takes
//! the target's default: 8 on TwinCAT 3 for x86/x64 (`--pack-mode` for a
//! target that differs, e.g. 4 on a CX7000). A structure is aligned as its
//! most aligned member and padded to a multiple of that. Consecutive `BIT`
//! members share a byte, the next member starts on the byte after them.

use std::cell::RefCell;
use std::collections::HashMap;

use crate::error::{Cause, DeclarationError, Place};
use crate::parse::{Body, TypeDecl, TypeExpr};
use crate::types::Elementary;

/// No image nests deeper than this; a deeper type contains itself.
const MAX_DEPTH: usize = 16;

/// A member as TwinCAT places it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Placed {
    pub name: String,
    pub line: usize,
    pub offset: usize,
    pub bit: Option<u8>,
    pub size: usize,
    /// With aliases resolved.
    pub data_type: TypeExpr,
}

/// A structure as TwinCAT lays it out.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Laid {
    pub name: String,
    pub place: Place,
    pub members: Vec<Placed>,
    pub size: usize,
    pub align: usize,
    /// Its `pack_mode` attribute, if it has one.
    pub pack_mode: Option<u8>,
}

/// Every type of a user's files, looked up case-insensitively as ST does.
#[derive(Debug, Clone)]
pub struct Declarations {
    types: Vec<TypeDecl>,
    /// Lower-case name → index into `types`.
    by_name: HashMap<String, usize>,
    default_pack_mode: u8,
    /// Size and alignment of each structure laid out so far: a type used by
    /// many members is laid out once, however deep the nesting.
    laid: RefCell<HashMap<usize, (usize, usize)>>,
}

impl Declarations {
    /// Refuses a name declared twice.
    pub fn new(types: Vec<TypeDecl>, default_pack_mode: u8) -> Result<Self, DeclarationError> {
        let mut by_name: HashMap<String, usize> = HashMap::new();
        for (i, t) in types.iter().enumerate() {
            if let Some(&first) = by_name.get(&t.name.to_ascii_lowercase()) {
                return Err(DeclarationError {
                    place: t.place.clone(),
                    cause: Cause::Duplicate {
                        name: t.name.clone(),
                        first: types[first].place.clone(),
                    },
                });
            }
            by_name.insert(t.name.to_ascii_lowercase(), i);
        }
        Ok(Declarations {
            types,
            by_name,
            default_pack_mode,
            laid: RefCell::default(),
        })
    }

    pub fn types(&self) -> &[TypeDecl] {
        &self.types
    }

    pub fn find(&self, name: &str) -> Option<&TypeDecl> {
        self.by_name
            .get(&name.to_ascii_lowercase())
            .map(|&i| &self.types[i])
    }

    /// The structure `name` laid out; `None` if it is no structure.
    pub fn lay_out(&self, name: &str) -> Result<Option<Laid>, DeclarationError> {
        match self.find(name) {
            Some(
                decl @ TypeDecl {
                    body: Body::Struct(_),
                    ..
                },
            ) => self.lay_out_struct(decl, 0).map(Some),
            _ => Ok(None),
        }
    }

    /// `data_type` with every alias replaced by what it names.
    pub fn resolve(
        &self,
        data_type: &TypeExpr,
        place: &Place,
    ) -> Result<TypeExpr, DeclarationError> {
        self.resolve_at(data_type, place, 0)
    }

    fn resolve_at(
        &self,
        data_type: &TypeExpr,
        place: &Place,
        depth: usize,
    ) -> Result<TypeExpr, DeclarationError> {
        let too_deep = |name: &str| DeclarationError {
            place: place.clone(),
            cause: Cause::TooDeep(name.to_string()),
        };
        match data_type {
            TypeExpr::Named(name) => match self.find(name) {
                None => Err(DeclarationError {
                    place: place.clone(),
                    cause: Cause::UnknownType(name.clone()),
                }),
                Some(_) if depth > MAX_DEPTH => Err(too_deep(name)),
                Some(TypeDecl {
                    body: Body::Alias(inner),
                    place,
                    ..
                }) => self.resolve_at(inner, place, depth + 1),
                Some(_) => Ok(data_type.clone()),
            },
            TypeExpr::Array { low, high, element } => Ok(TypeExpr::Array {
                low: *low,
                high: *high,
                element: Box::new(self.resolve_at(element, place, depth + 1)?),
            }),
            other => Ok(other.clone()),
        }
    }

    fn lay_out_struct(&self, decl: &TypeDecl, depth: usize) -> Result<Laid, DeclarationError> {
        let Body::Struct(members) = &decl.body else {
            unreachable!("only structures are laid out")
        };
        let cap = match decl.pack_mode.unwrap_or(self.default_pack_mode) {
            0 => 1,
            n => usize::from(n),
        };
        let mut placed = Vec::new();
        let mut cursor = 0usize;
        // The byte and the next bit of a run of BITs.
        let mut bits: Option<(usize, u8)> = None;
        let mut align = 1;
        for member in members {
            let place = Place {
                file: decl.place.file.clone(),
                line: member.line,
            };
            let data_type = self.resolve(&member.data_type, &place)?;
            if data_type == TypeExpr::Elementary(Elementary::Bit) {
                let (byte, bit) = match bits {
                    Some((byte, bit)) if bit < 8 => (byte, bit),
                    _ => (cursor, 0),
                };
                cursor = byte + 1;
                bits = Some((byte, bit + 1));
                placed.push(Placed {
                    name: member.name.clone(),
                    line: member.line,
                    offset: byte,
                    bit: Some(bit),
                    size: 0,
                    data_type,
                });
                continue;
            }
            bits = None;
            let (size, own_align) = self.size_align(&data_type, &place, depth)?;
            let member_align = own_align.min(cap).max(1);
            align = align.max(member_align);
            cursor = cursor.div_ceil(member_align) * member_align;
            placed.push(Placed {
                name: member.name.clone(),
                line: member.line,
                offset: cursor,
                bit: None,
                size,
                data_type,
            });
            cursor = cursor.checked_add(size).ok_or_else(|| DeclarationError {
                place: place.clone(),
                cause: Cause::TooDeep(decl.name.clone()),
            })?;
        }
        Ok(Laid {
            name: decl.name.clone(),
            place: decl.place.clone(),
            members: placed,
            size: cursor.div_ceil(align) * align,
            align,
            pack_mode: decl.pack_mode,
        })
    }

    /// Bytes `data_type` takes as TwinCAT lays it out (a `BIT` none).
    pub fn size_of(&self, data_type: &TypeExpr, place: &Place) -> Result<usize, DeclarationError> {
        self.size_align(data_type, place, 0).map(|(size, _)| size)
    }

    /// Size and natural alignment of a resolved type.
    fn size_align(
        &self,
        data_type: &TypeExpr,
        place: &Place,
        depth: usize,
    ) -> Result<(usize, usize), DeclarationError> {
        if depth > MAX_DEPTH {
            return Err(DeclarationError {
                place: place.clone(),
                cause: Cause::TooDeep(format!("{data_type:?}")),
            });
        }
        match data_type {
            TypeExpr::Elementary(e) => Ok((e.size(), e.size().max(1))),
            TypeExpr::String { bytes } => Ok((*bytes, 1)),
            TypeExpr::Array { low, high, element } => {
                let (size, align) = self.size_align(element, place, depth + 1)?;
                let count = crate::types::element_count(*low, *high);
                let total = size.checked_mul(count).ok_or_else(|| DeclarationError {
                    place: place.clone(),
                    cause: Cause::EmptyArray {
                        low: *low,
                        high: *high,
                    },
                })?;
                Ok((total, align))
            }
            TypeExpr::Named(name) => match self.find(name) {
                Some(
                    decl @ TypeDecl {
                        body: Body::Struct(_),
                        ..
                    },
                ) => {
                    let key = self.by_name[&name.to_ascii_lowercase()];
                    if let Some(known) = self.laid.borrow().get(&key) {
                        return Ok(*known);
                    }
                    let laid = self.lay_out_struct(decl, depth + 1)?;
                    self.laid.borrow_mut().insert(key, (laid.size, laid.align));
                    Ok((laid.size, laid.align))
                }
                _ => {
                    let resolved = self.resolve(data_type, place)?;
                    self.size_align(&resolved, place, depth + 1)
                }
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse::parse;
    use crate::source::Source;

    fn laid(text: &str, default: u8) -> Laid {
        let types = parse(&Source {
            file: "t.st".into(),
            text: text.into(),
            first_line: 1,
        })
        .expect("parses");
        let name = types[0].name.clone();
        Declarations::new(types, default)
            .expect("no duplicates")
            .lay_out(&name)
            .expect("sized")
            .expect("a structure")
    }

    /// Infosys's own sample: 8 bytes packed, 10 at pack_mode 2, 12 at 4.
    #[test]
    fn the_infosys_sample_has_its_documented_sizes() {
        let body = "TYPE str_Test :\nSTRUCT\nbyTest1 : BYTE;\niTest : DINT;\nbyTest2 : BYTE;\nnValue : INT;\nEND_STRUCT\nEND_TYPE";
        for (mode, size) in [(0, 8), (2, 10), (4, 12), (8, 12)] {
            let text = format!("{{attribute 'pack_mode' := '{mode}'}}\n{body}");
            assert_eq!(laid(&text, 8).size, size, "pack_mode {mode}");
        }
        assert_eq!(laid(body, 8).size, 12, "the x64 default aligns to 4 here");
        assert_eq!(laid(body, 0).size, 8);
    }

    #[test]
    fn bits_share_a_byte_and_the_next_member_follows_it() {
        let text = "{attribute 'pack_mode' := '0'}\nTYPE Q :\nSTRUCT\nlen : BYTE;\nEDL : BIT;\nBSR : BIT;\nESI : BIT;\ncobId : UDINT;\nEND_STRUCT\nEND_TYPE";
        let q = laid(text, 8);
        let placed: Vec<(usize, Option<u8>)> =
            q.members.iter().map(|m| (m.offset, m.bit)).collect();
        assert_eq!(
            placed,
            [
                (0, None),
                (1, Some(0)),
                (1, Some(1)),
                (1, Some(2)),
                (2, None)
            ]
        );
        assert_eq!(q.size, 6);
    }
}
