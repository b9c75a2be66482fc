//! Buffers (§3.6.1) and accessor data (§3.6.2), read with every range checked.

use json::accessor::{ComponentType, GenericComponentType, IndexComponentType, Type as AccessorType};
use json::validation::Checked;

use super::container::{decode_data_uri, is_data_uri};
use super::{Loader, SceneError, json};

/// Upper bound on the elements of the accessors that have no buffer view (all zeros,
/// §3.6.2.3), each and all of one file together, so that a hostile `count` cannot make the
/// loader allocate without limit.
pub(super) const MAX_ZERO_ACCESSOR_ELEMENTS: usize = 1 << 22;

// ---------------------------------------------------------------------------------------
// Accessor data (§3.6.2)
// ---------------------------------------------------------------------------------------

/// A validated window on an accessor's elements: every element `i < count` lies in `bytes`.
struct Elements<'b> {
    bytes: &'b [u8],
    offset: usize,
    stride: usize,
    component: ComponentType,
    normalized: bool,
}

/// What [`Loader::locate`] looks for: `count` elements of `components` × `component` in buffer
/// view `view` from byte `offset`, `normalized` integers or not; `tight` ignores the view's
/// byteStride (sparse data).
#[derive(Clone, Copy)]
struct Span {
    view: usize,
    offset: usize,
    count: usize,
    component: ComponentType,
    components: usize,
    normalized: bool,
    tight: bool,
}
impl Elements<'_> {
    /// The bytes of component `c` of element `i`.
    fn raw(&self, i: usize, c: usize) -> Option<&[u8]> {
        let size = self.component.size();
        let at = i.checked_mul(self.stride)?.checked_add(self.offset)?.checked_add(c.checked_mul(size)?)?;
        self.bytes.get(at..at.checked_add(size)?)
    }

    /// Component `c` of element `i` as a float; normalized integers map to [0, 1] or
    /// [−1, 1] as in glTF 2.0 spec §3.11 (Animations, "Normalized integers").
    fn float(&self, i: usize, c: usize) -> f32 {
        let n = self.normalized;
        match (self.component, self.raw(i, c)) {
            (ComponentType::F32, Some(&[a, b, c, d])) => f32::from_le_bytes([a, b, c, d]),
            (ComponentType::U8, Some(&[a])) => {
                if n {
                    f32::from(a) / 255.0
                } else {
                    f32::from(a)
                }
            }
            (ComponentType::I8, Some(&[a])) => {
                let v = f32::from(a as i8);
                if n { (v / 127.0).max(-1.0) } else { v }
            }
            (ComponentType::U16, Some(&[a, b])) => {
                let v = f32::from(u16::from_le_bytes([a, b]));
                if n { v / 65535.0 } else { v }
            }
            (ComponentType::I16, Some(&[a, b])) => {
                let v = f32::from(i16::from_le_bytes([a, b]));
                if n { (v / 32767.0).max(-1.0) } else { v }
            }
            (ComponentType::U32, Some(&[a, b, c, d])) => u32::from_le_bytes([a, b, c, d]) as f32,
            _ => 0.0,
        }
    }

    /// Component `c` of element `i` as an unsigned integer (indices).
    fn uint(&self, i: usize, c: usize) -> u32 {
        match self.raw(i, c) {
            Some(&[a]) => u32::from(a),
            Some(&[a, b]) => u32::from(u16::from_le_bytes([a, b])),
            Some(&[a, b, c, d]) => u32::from_le_bytes([a, b, c, d]),
            _ => 0,
        }
    }
}

/// Converts a JSON size to usize; values that do not fit saturate and then fail the range checks.
fn to_usize(v: u64) -> usize {
    usize::try_from(v).unwrap_or(usize::MAX)
}

impl Loader<'_> {
    /// Loads every buffer (§3.6.1): the GLB BIN chunk, a `data:` URI or a file in the scene
    /// folder; each must hold at least its declared `byteLength`, and is cut to that length
    /// so that all later range checks are against the declared size.
    pub(super) fn load_buffers(&mut self, bin: Option<&[u8]>) -> Result<(), SceneError> {
        let root = self.root;
        for (i, b) in root.buffers.iter().enumerate() {
            let declared = b.byte_length.0;
            let (uri, mut data) = match b.uri.as_deref() {
                // A meshopt fallback buffer without data: only compressed views point into it,
                // and they are decoded from their own buffers (see `compression.rs`).
                None if super::compression::is_fallback(b) => {
                    self.buffers.push(Vec::new());
                    continue;
                }
                None => match bin {
                    Some(bin) if i == 0 => ("GLB BIN chunk".to_string(), bin.to_vec()),
                    _ => {
                        return Err(SceneError::MissingBuffer {
                            file: self.file.to_string(),
                            buffer: i,
                            uri: String::new(),
                            reason: "it has no uri and is not the first buffer of a .glb with a BIN chunk".to_string(),
                        });
                    }
                },
                Some(uri) if is_data_uri(uri) => {
                    let data = decode_data_uri(uri).map_err(|reason| SceneError::BadDataUri {
                        file: self.file.to_string(),
                        what: format!("buffer {i}"),
                        reason,
                    })?;
                    ("data URI".to_string(), data)
                }
                Some(uri) => {
                    let data = self.read_external(uri, &format!("buffer {i}"), |reason| SceneError::MissingBuffer {
                        file: self.file.to_string(),
                        buffer: i,
                        uri: uri.to_string(),
                        reason,
                    })?;
                    (uri.to_string(), data)
                }
            };
            if (data.len() as u64) < declared {
                return Err(SceneError::BufferTooShort {
                    file: self.file.to_string(),
                    buffer: i,
                    uri,
                    declared,
                    actual: data.len(),
                });
            }
            data.truncate(to_usize(declared));
            self.buffers.push(data);
        }
        Ok(())
    }

    /// The bytes of buffer view `view` (§3.6.2.2), checked against its buffer; for a
    /// compressed view, its decoded bytes.
    pub(super) fn view_bytes(&self, view: usize) -> Result<&[u8], String> {
        if let Some(decoded) = self.decoded_views.get(&view) {
            return Ok(decoded.bytes());
        }
        let v = self.root.buffer_views.get(view).ok_or_else(|| format!("buffer view {view} does not exist"))?;
        let b = v.buffer.value();
        let buffer = self
            .buffers
            .get(b)
            .ok_or_else(|| format!("buffer view {view} refers to buffer {b}, which does not exist"))?;
        let start = to_usize(v.byte_offset.map_or(0, |o| o.0));
        let len = to_usize(v.byte_length.0);
        start.checked_add(len).and_then(|end| buffer.get(start..end)).ok_or_else(|| {
            format!(
                "buffer view {view} covers {len} bytes from offset {start}, but buffer {b} has only {} bytes",
                buffer.len()
            )
        })
    }

    /// Locates the elements of `span` (of accessor `accessor`, read as `what`), checking
    /// offset + (count − 1) · stride + element size ≤ view length (§3.6.2.4) with checked
    /// arithmetic.
    fn locate(&self, accessor: usize, what: &str, span: Span) -> Result<Elements<'_>, SceneError> {
        let Span { view, offset, count, component, components, normalized, tight } = span;
        let out_of_range = |reason: String| SceneError::AccessorOutOfRange {
            file: self.file.to_string(),
            accessor,
            what: what.to_string(),
            reason,
        };
        let bytes = self.view_bytes(view).map_err(out_of_range)?;
        let element = component.size() * components;
        let stride = match self.root.buffer_views.get(view).and_then(|v| v.byte_stride) {
            Some(s) if !tight => s.0,
            _ => element,
        };
        if stride < element {
            return Err(self.invalid(format!(
                "buffer view {view} has byteStride {stride}, smaller than the {element}-byte elements of accessor {accessor} ({what})"
            )));
        }
        if count > 0 {
            let end = (count - 1)
                .checked_mul(stride)
                .and_then(|x| x.checked_add(offset))
                .and_then(|x| x.checked_add(element));
            if end.is_none_or(|e| e > bytes.len()) {
                return Err(out_of_range(format!(
                    "{count} elements of {element} bytes (stride {stride}) from offset {offset} need {} bytes, but buffer view {view} has {}",
                    end.map_or_else(|| "more than 2^64".to_string(), |e| e.to_string()),
                    bytes.len()
                )));
            }
        }
        Ok(Elements { bytes, offset, stride, component, normalized })
    }

    /// Reads accessor `index` into a flat vector of `T` (count × components), with `get`
    /// converting one component. Checks the type against `types`, the component type with
    /// `component_ok`, all ranges, and applies sparse substitution (§3.6.2.3).
    fn read_accessor<T: Copy + Default>(
        &self,
        index: usize,
        what: &str,
        types: &[AccessorType],
        component_ok: impl Fn(ComponentType) -> bool,
        get: impl Fn(&Elements<'_>, usize, usize) -> T,
    ) -> Result<(Vec<T>, usize), SceneError> {
        let acc = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| self.invalid(format!("{what} refers to accessor {index}, which does not exist")))?;
        let Checked::Valid(ty) = acc.type_ else {
            return Err(self.invalid(format!("accessor {index} ({what}) has an unknown type")));
        };
        if !types.contains(&ty) {
            return Err(self.invalid(format!("accessor {index} ({what}) has type {ty:?}, expected one of {types:?}")));
        }
        let Checked::Valid(GenericComponentType(component)) = acc.component_type else {
            return Err(self.invalid(format!("accessor {index} ({what}) has an unknown componentType")));
        };
        if !component_ok(component) {
            return Err(self.invalid(format!(
                "accessor {index} ({what}) has componentType {component:?}, which is not allowed here"
            )));
        }
        let n = ty.multiplicity();
        let count = to_usize(acc.count.0);
        let out_of_range = |reason: String| SceneError::AccessorOutOfRange {
            file: self.file.to_string(),
            accessor: index,
            what: what.to_string(),
            reason,
        };
        // Checked after the data is located (a count past its data is reported as such) and
        // before anything is allocated: every read of the file counts (see `Budget`).
        let spend = |loader: &Self| -> Result<(), SceneError> {
            if super::spend(&loader.budget.values, count.saturating_mul(n)) {
                return Ok(());
            }
            Err(SceneError::Unsupported {
                file: loader.file.to_string(),
                message: format!(
                    "accessor {index} ({what}) has {count} elements: reading it would take the file past the {} \
                     accessor values GI Lab reads per file (an accessor is read again by every primitive that \
                     uses it)",
                    super::MAX_VALUES_PER_FILE
                ),
            })
        };
        let mut out = match acc.buffer_view {
            Some(view) => {
                let offset = to_usize(acc.byte_offset.map_or(0, |o| o.0));
                let span = Span {
                    view: view.value(),
                    offset,
                    count,
                    component,
                    components: n,
                    normalized: acc.normalized,
                    tight: false,
                };
                let el = self.locate(index, what, span)?;
                spend(self)?;
                let mut out = Vec::with_capacity(count * n); // bounded: the elements were found in the buffer
                for i in 0..count {
                    for c in 0..n {
                        out.push(get(&el, i, c));
                    }
                }
                out
            }
            None => {
                if acc.sparse.is_none() || count > MAX_ZERO_ACCESSOR_ELEMENTS {
                    return Err(out_of_range(format!(
                        "it has no buffer view and {}",
                        if acc.sparse.is_none() { "no sparse data".to_string() } else { format!("{count} elements") }
                    )));
                }
                if !super::spend(&self.budget.zeros, count) {
                    return Err(out_of_range(format!(
                        "it has no buffer view and {count} elements, which would take the file past the \
                         {MAX_ZERO_ACCESSOR_ELEMENTS} elements of zero-filled accessors GI Lab makes per file (an \
                         accessor is read again by every primitive that uses it)"
                    )));
                }
                spend(self)?;
                vec![T::default(); count * n]
            }
        };
        if let Some(sparse) = &acc.sparse {
            let sparse_count = to_usize(sparse.count.0);
            let Checked::Valid(IndexComponentType(index_type)) = sparse.indices.component_type else {
                return Err(self.invalid(format!("accessor {index} ({what}) has sparse indices of an unknown type")));
            };
            let indices = self.locate(
                index,
                what,
                Span {
                    view: sparse.indices.buffer_view.value(),
                    offset: to_usize(sparse.indices.byte_offset.0),
                    count: sparse_count,
                    component: index_type,
                    components: 1,
                    normalized: false,
                    tight: true,
                },
            )?;
            let values = self.locate(
                index,
                what,
                Span {
                    view: sparse.values.buffer_view.value(),
                    offset: to_usize(sparse.values.byte_offset.0),
                    count: sparse_count,
                    component,
                    components: n,
                    normalized: acc.normalized,
                    tight: true,
                },
            )?;
            for k in 0..sparse_count {
                let i = indices.uint(k, 0) as usize;
                if i >= count {
                    return Err(out_of_range(format!("sparse index {i} is not below the accessor's count {count}")));
                }
                for c in 0..n {
                    if let Some(slot) = out.get_mut(i * n + c) {
                        *slot = get(&values, k, c);
                    }
                }
            }
        }
        Ok((out, n))
    }

    /// Reads a float accessor of one of `types` (any component type; integers are converted,
    /// normalized ones per §3.11).
    pub(super) fn read_floats(&self, index: usize, what: &str, types: &[AccessorType]) -> Result<Vec<f32>, SceneError> {
        self.read_accessor(index, what, types, |_| true, |el, i, c| el.float(i, c)).map(|(v, _)| v)
    }

    /// Reads an index accessor: SCALAR of unsigned byte, short or int (§3.7.2.1).
    pub(super) fn read_indices(&self, index: usize, what: &str) -> Result<Vec<u32>, SceneError> {
        let ok = |c| matches!(c, ComponentType::U8 | ComponentType::U16 | ComponentType::U32);
        self.read_accessor(index, what, &[AccessorType::Scalar], ok, |el, i, c| el.uint(i, c)).map(|(v, _)| v)
    }
}
