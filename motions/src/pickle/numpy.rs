//! NumPy's side of a pickle: dtypes, arrays rebuilt from `_reconstruct` + BUILD state (protocols
//! 2-4) or `_frombuffer` (protocol 5), and scalars, all decoded to f64 in C order.

use super::Value;

/// A NumPy array read from a pickle.
#[derive(Debug, Clone, PartialEq)]
pub struct Array {
    /// Its shape.
    pub shape: Vec<usize>,
    /// Its values in C (row-major) order.
    pub data: Vec<f64>,
}

/// A NumPy element type: kind (`f`, `i`, `u`, `b`), size in bytes and byte order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dtype {
    pub(super) kind: u8,
    pub(super) size: usize,
    pub(super) big_endian: bool,
}

/// `numpy.dtype(code, align, copy)`: codes as `f8`, `<i4`, `float32`.
pub(super) fn dtype(code: Option<&Value>) -> Result<Dtype, String> {
    let Some(Value::Str(code)) = code else {
        return Err("numpy.dtype without a type code".into());
    };
    let (big_endian, body) = match code.as_bytes().first() {
        Some(b'>') => (true, &code[1..]),
        Some(b'<' | b'=' | b'|') => (false, &code[1..]),
        _ => (false, code.as_str()),
    };
    let named = match body {
        "float64" | "double" => "f8",
        "float32" | "single" => "f4",
        "int64" => "i8",
        "int32" => "i4",
        "uint8" => "u1",
        "bool" => "b1",
        other => other,
    };
    let kind = named.as_bytes().first().copied().unwrap_or(0);
    let size: usize = named.get(1..).and_then(|s| s.parse().ok()).unwrap_or(0);
    let known = matches!(
        (kind, size),
        (b'f', 4 | 8) | (b'i', 1 | 2 | 4 | 8) | (b'u', 1 | 2 | 4 | 8) | (b'b', 1)
    );
    if !known {
        return Err(format!(
            "NumPy type '{code}' is not read here (floats, integers, bools)"
        ));
    }
    Ok(Dtype {
        kind,
        size,
        big_endian,
    })
}

/// Decodes raw element bytes into f64 values.
fn decode(bytes: &[u8], d: Dtype) -> Result<Vec<f64>, String> {
    if !bytes.len().is_multiple_of(d.size) {
        return Err(format!(
            "{} bytes of data for elements of {} bytes",
            bytes.len(),
            d.size
        ));
    }
    Ok(bytes
        .chunks_exact(d.size)
        .map(|c| {
            let mut b = [0u8; 8];
            if d.big_endian {
                b[8 - d.size..].copy_from_slice(c);
                b.reverse();
            } else {
                b[..d.size].copy_from_slice(c);
            }
            let signed = |bits: u32| {
                let shift = 64 - bits;
                ((i64::from_le_bytes(b) << shift) >> shift) as f64
            };
            match (d.kind, d.size) {
                (b'f', 4) => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                (b'f', _) => f64::from_le_bytes(b),
                (b'i', n) => signed(8 * n as u32),
                _ => u64::from_le_bytes(b) as f64,
            }
        })
        .collect())
}

fn shape_of(value: &Value) -> Result<Vec<usize>, String> {
    match value {
        Value::Tuple(dims) => dims
            .iter()
            .map(|d| match d {
                Value::Int(n) if *n >= 0 => Ok(*n as usize),
                other => Err(format!("an array dimension of {other:?}")),
            })
            .collect(),
        other => Err(format!("an array shape of {other:?}")),
    }
}

/// An array of `shape` from its raw bytes, Fortran order turned into C order.
fn array(shape: Vec<usize>, d: Dtype, fortran: bool, bytes: &[u8]) -> Result<Array, String> {
    let count = shape
        .iter()
        .try_fold(1usize, |acc, &n| acc.checked_mul(n))
        .ok_or("an array shape that overflows")?;
    let values = decode(bytes, d)?;
    if values.len() != count {
        return Err(format!(
            "an array of shape {shape:?} holds {} values",
            values.len()
        ));
    }
    let data = if fortran && shape.len() > 1 {
        (0..count)
            .map(|c| {
                // C index c -> multi-index -> Fortran offset.
                let (mut rest, mut offset, mut stride) = (c, 0, 1);
                let mut index = vec![0; shape.len()];
                for (k, &n) in shape.iter().enumerate().rev() {
                    index[k] = rest % n;
                    rest /= n;
                }
                for (k, &n) in shape.iter().enumerate() {
                    offset += index[k] * stride;
                    stride *= n;
                }
                values[offset]
            })
            .collect()
    } else {
        values
    };
    Ok(Array { shape, data })
}

/// `ndarray.__setstate__((version, shape, dtype, is_fortran, data))`.
pub(super) fn array_state(state: &Value) -> Result<Array, String> {
    let Value::Tuple(items) = state else {
        return Err("an array state that is not a tuple".into());
    };
    let (shape, d, fortran, data) = match items.as_slice() {
        [Value::Int(_), shape, Value::Dtype(d), Value::Bool(f), data] => (shape, d, *f, data),
        [shape, Value::Dtype(d), Value::Bool(f), data] => (shape, d, *f, data),
        _ => return Err("an array state of an unknown form (object arrays are not read)".into()),
    };
    let Value::Bytes(bytes) = data else {
        return Err("an array whose data are not bytes (object arrays are not read)".into());
    };
    array(shape_of(shape)?, *d, fortran, bytes)
}

/// Protocol 5's `_frombuffer(buffer, dtype, shape, order)`.
pub(super) fn from_buffer(args: &[Value]) -> Result<Value, String> {
    match args {
        [
            Value::Bytes(bytes),
            Value::Dtype(d),
            shape,
            Value::Str(order),
        ] => Ok(Value::Array(array(
            shape_of(shape)?,
            *d,
            order == "F",
            bytes,
        )?)),
        _ => Err("_frombuffer with arguments of an unknown form".into()),
    }
}

/// `numpy.core.multiarray.scalar(dtype, bytes)`: a NumPy scalar.
pub(super) fn scalar(args: &[Value]) -> Result<Value, String> {
    match args {
        [Value::Dtype(d), Value::Bytes(bytes)] => match decode(bytes, *d)?.as_slice() {
            [v] => Ok(Value::Float(*v)),
            _ => Err("a NumPy scalar of several values".into()),
        },
        _ => Err("a NumPy scalar of an unknown form".into()),
    }
}
