//! Reading named numeric arrays out of .npz files (as written by `np.savez`/`np.savez_compressed`)
//! with the dtype flexibility real SMPL and AMASS files need, and errors naming file and key;
//! and writing arrays into one, an entry at a time.

use std::io::{BufReader, Read, Seek, Write};
use std::path::{Path, PathBuf};

use npyz::npz::{NpzArchive, NpzWriter};
use npyz::{DType, TypeChar, WriterBuilder};

use crate::error::{Error, Result};

/// An array read from an npz: its shape and values converted to `f64`.
#[derive(Debug, Clone)]
pub struct Array {
    /// The array's shape (empty for a 0-d scalar).
    pub shape: Vec<usize>,
    /// Values in C order.
    pub data: Vec<f64>,
}

/// An opened npz file whose arrays are read on demand.
pub struct Npz<R: Read + Seek> {
    path: PathBuf,
    archive: NpzArchive<R>,
    /// Bytes an array may decode to (see [`array_byte_limit`]).
    array_limit: u64,
}

/// The most bytes one array may decode to: 256 MiB, or 64 times the archive's size (real
/// body models compress a few times at most), so a damaged shape never sizes an allocation.
fn array_byte_limit(archive_bytes: u64) -> u64 {
    (256u64 << 20).max(archive_bytes.saturating_mul(64))
}

/// Writes `data` (C order, `shape`) as the entry `name` of an npz being written, deflated as
/// `np.savez_compressed` does. The array is serialized to memory first and handed to the zip
/// writer in one piece: npyz's own array writer passes it one element at a time, and flate2
/// clears its whole output buffer on every write (the default body model's arrays took 4 s to
/// write that way, 0.1 s this way).
pub fn write_array<T, W>(
    npz: &mut NpzWriter<W>,
    name: &str,
    shape: &[u64],
    data: &[T],
) -> std::io::Result<()>
where
    T: npyz::AutoSerialize + Copy,
    W: Write + Seek,
{
    let mut npy = Vec::with_capacity(128 + std::mem::size_of_val(data));
    let mut writer = npyz::WriteOptions::new()
        .default_dtype()
        .shape(shape)
        .writer(&mut npy)
        .begin_nd()?;
    writer.extend(data.iter().copied())?;
    writer.finish()?;
    write_entry(npz, name, &npy)
}

/// Writes `text` as the 0-d unicode entry `name` (`np.savez(gender="neutral")`'s `<U7`).
pub fn write_text<W: Write + Seek>(
    npz: &mut NpzWriter<W>,
    name: &str,
    text: &str,
) -> std::io::Result<()> {
    let dtype = format!("<U{}", text.chars().count().max(1))
        .parse()
        .map_err(std::io::Error::other)?;
    let mut npy = Vec::new();
    let mut writer = npyz::WriteOptions::<str>::new()
        .dtype(DType::Plain(dtype))
        .shape(&[])
        .writer(&mut npy)
        .begin_nd()?;
    writer.push(text)?;
    writer.finish()?;
    write_entry(npz, name, &npy)
}

/// One `.npy` file's bytes as the archive's entry for the array `name`.
fn write_entry<W: Write + Seek>(
    npz: &mut NpzWriter<W>,
    name: &str,
    npy: &[u8],
) -> std::io::Result<()> {
    let zip = npz.zip_writer();
    zip.start_file(
        npyz::npz::file_name_from_array_name(name),
        Default::default(),
    )
    .map_err(std::io::Error::other)?;
    zip.write_all(npy)
}

impl Npz<std::io::BufReader<std::fs::File>> {
    /// Opens `path`, recognising a Python pickle (a common mistake with SMPL files) by its magic.
    pub fn open(path: &Path) -> Result<Self> {
        let mut head = [0u8; 2];
        let (mut file, _) = files::open_bounded(path, files::limits::ARRAYS, "NumPy archive")?;
        let n = file.read(&mut head).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        if n == 2 && head[0] == 0x80 && head[1] <= 5 {
            return Err(Error::Pickle {
                path: path.to_path_buf(),
            });
        }
        // The file already opened (and checked), not the path again.
        Self::from_reader(std::io::BufReader::new(file), path)
    }
}

impl<R: Read + Seek> Npz<R> {
    /// Wraps an npz held in any seekable reader (e.g. bytes compiled into the binary); `path`
    /// is only used in error messages.
    pub fn from_reader(mut reader: R, path: &Path) -> Result<Self> {
        let io = |source| Error::Io {
            path: path.to_path_buf(),
            source,
        };
        let bytes = reader.seek(std::io::SeekFrom::End(0)).map_err(io)?;
        reader.rewind().map_err(io)?;
        let archive = NpzArchive::new(reader).map_err(|e| Error::NotNpz {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        Ok(Self {
            path: path.to_path_buf(),
            archive,
            array_limit: array_byte_limit(bytes),
        })
    }

    /// The file this archive came from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Names of the arrays in the archive.
    pub fn keys(&self) -> Vec<String> {
        self.archive.array_names().map(str::to_string).collect()
    }

    /// Whether the archive holds `key`.
    pub fn has(&self, key: &str) -> bool {
        self.archive.array_names().any(|k| k == key)
    }

    fn bad(&self, key: &str, problem: impl Into<String>) -> Error {
        bad_array(&self.path, key, problem)
    }

    /// Reads a numeric array (float, signed or unsigned integer, any width, little or big
    /// endian) as `f64`. Returns `None` if the key is absent.
    pub fn numeric(&mut self, key: &str) -> Result<Option<Array>> {
        let path = self.path.clone();
        let Some(file) = entry(&mut self.archive, &path, key)? else {
            return Ok(None);
        };
        let shape: Vec<usize> = file.shape().iter().map(|&s| s as usize).collect();
        let DType::Plain(ts) = file.dtype() else {
            return Err(bad_array(&path, key, "structured arrays are not supported"));
        };
        let size = ts.size_field();
        let bytes = shape
            .iter()
            .try_fold(size, |total, &n| total.checked_mul(n as u64))
            .filter(|&b| b <= self.array_limit);
        if bytes.is_none() {
            return Err(bad_array(
                &path,
                key,
                format!(
                    "shape {shape:?} of {size}-byte values is more than the {} bytes an array \
                     of this file may have",
                    self.array_limit
                ),
            ));
        }
        // NumPy writes `np.asfortranarray` data column-major; it is reordered below.
        let fortran = file.order() == npyz::Order::Fortran;
        let io = |e: std::io::Error| Error::BadArray {
            path: path.clone(),
            key: key.to_string(),
            problem: e.to_string(),
        };
        let data: Vec<f64> = match (ts.type_char(), size) {
            (TypeChar::Float, 8) => file.into_vec::<f64>().map_err(io)?,
            (TypeChar::Float, 4) => file
                .into_vec::<f32>()
                .map_err(io)?
                .into_iter()
                .map(f64::from)
                .collect(),
            (TypeChar::Int, 8) => to_f64(file.into_vec::<i64>().map_err(io)?),
            (TypeChar::Int, 4) => to_f64(file.into_vec::<i32>().map_err(io)?),
            (TypeChar::Int, 2) => to_f64(file.into_vec::<i16>().map_err(io)?),
            (TypeChar::Int, 1) => to_f64(file.into_vec::<i8>().map_err(io)?),
            (TypeChar::Uint, 8) => to_f64(file.into_vec::<u64>().map_err(io)?),
            (TypeChar::Uint, 4) => to_f64(file.into_vec::<u32>().map_err(io)?),
            (TypeChar::Uint, 2) => to_f64(file.into_vec::<u16>().map_err(io)?),
            (TypeChar::Uint, 1) => to_f64(file.into_vec::<u8>().map_err(io)?),
            (TypeChar::Object, _) => {
                return Err(bad_array(
                    &path,
                    key,
                    "holds pickled Python objects (e.g. a chumpy or scipy.sparse array); \
                     save it as a plain numpy array",
                ));
            }
            _ => {
                return Err(bad_array(
                    &path,
                    key,
                    format!("unsupported dtype '{ts}' (expected numbers)"),
                ));
            }
        };
        let expected: usize = shape.iter().product();
        if data.len() != expected {
            return Err(bad_array(&path, key, "truncated array data"));
        }
        let data = if fortran {
            fortran_to_c(&shape, &data)
        } else {
            data
        };
        Ok(Some(Array { shape, data }))
    }

    /// Reads a required numeric array, checking its shape; `None` in `shape` matches any size.
    pub fn required(&mut self, key: &str, shape: &[Option<usize>], what: &str) -> Result<Array> {
        let array = self.numeric(key)?.ok_or_else(|| Error::MissingKey {
            path: self.path.clone(),
            key: key.to_string(),
            what: what.to_string(),
        })?;
        self.check_shape(key, &array, shape)?;
        Ok(array)
    }

    /// Checks an array's shape against a pattern (`None` = any size in that axis).
    pub fn check_shape(&self, key: &str, array: &Array, shape: &[Option<usize>]) -> Result<()> {
        let ok = array.shape.len() == shape.len()
            && array
                .shape
                .iter()
                .zip(shape)
                .all(|(&n, want)| want.is_none_or(|w| w == n));
        if ok {
            Ok(())
        } else {
            let want: Vec<String> = shape
                .iter()
                .map(|s| s.map_or("N".to_string(), |n| n.to_string()))
                .collect();
            Err(self.bad(
                key,
                format!("shape {:?}, expected ({})", array.shape, want.join(", ")),
            ))
        }
    }

    /// Checks that every value of an array is finite.
    pub fn check_finite(&self, key: &str, array: &Array) -> Result<()> {
        match array.data.iter().position(|v| !v.is_finite()) {
            None => Ok(()),
            Some(i) => Err(self.bad(key, format!("non-finite value at flat index {i}"))),
        }
    }

    /// Reads a string array (numpy unicode `<U..` or bytes `|S..`), e.g. AMASS's 0-d `gender`.
    pub fn strings(&mut self, key: &str) -> Result<Option<Vec<String>>> {
        let path = self.path.clone();
        let Some(file) = entry(&mut self.archive, &path, key)? else {
            return Ok(None);
        };
        let is_unicode =
            matches!(file.dtype(), DType::Plain(ref ts) if ts.type_char() == TypeChar::UnicodeStr);
        let is_bytes =
            matches!(file.dtype(), DType::Plain(ref ts) if ts.type_char() == TypeChar::ByteStr);
        let io = |e: std::io::Error| Error::BadArray {
            path: path.clone(),
            key: key.to_string(),
            problem: e.to_string(),
        };
        if is_unicode {
            Ok(Some(file.into_vec::<String>().map_err(io)?))
        } else if is_bytes {
            let raw = file.into_vec::<Vec<u8>>().map_err(io)?;
            Ok(Some(
                raw.into_iter()
                    .map(|b| {
                        String::from_utf8_lossy(&b)
                            .trim_end_matches('\0')
                            .to_string()
                    })
                    .collect(),
            ))
        } else {
            Err(Error::BadArray {
                path,
                key: key.to_string(),
                problem: format!(
                    "expected a string array, found dtype {}",
                    file.dtype().descr()
                ),
            })
        }
    }
}

/// The array `key`'s `.npy` entry in `archive` (read from `path`), opened and buffered; `None`
/// where the archive has no such entry. Buffered because npyz reads an array a value at a time,
/// and every read of a zip entry pays for a checksum update and an inflate call (the default
/// body model took 0.3 s to read that way, most of a short command's time).
fn entry<'a, R: Read + Seek>(
    archive: &'a mut NpzArchive<R>,
    path: &Path,
    key: &str,
) -> Result<Option<npyz::NpyFile<BufReader<npyz::zip::read::ZipFile<'a>>>>> {
    let name = npyz::npz::file_name_from_array_name(key);
    let entry = match archive.zip_archive().by_name(&name) {
        Ok(entry) => entry,
        Err(npyz::zip::result::ZipError::FileNotFound) => return Ok(None),
        Err(e) => return Err(bad_array(path, key, e.to_string())),
    };
    npyz::NpyFile::new(BufReader::with_capacity(1 << 16, entry))
        .map(Some)
        .map_err(|e| bad_array(path, key, e.to_string()))
}

fn bad_array(path: &Path, key: &str, problem: impl Into<String>) -> Error {
    Error::BadArray {
        path: path.to_path_buf(),
        key: key.to_string(),
        problem: problem.into(),
    }
}

/// Integer arrays to f64 (exact below 2^53; SMPL's u32::MAX "no parent" sentinel is exact).
fn to_f64<T: Copy + TryInto<i128>>(v: Vec<T>) -> Vec<f64> {
    v.into_iter()
        .map(|x| x.try_into().map_or(f64::NAN, |i: i128| i as f64))
        .collect()
}

/// Values stored column-major (Fortran order: the first index fastest) in row-major (C) order.
fn fortran_to_c(shape: &[usize], data: &[f64]) -> Vec<f64> {
    let mut strides = Vec::with_capacity(shape.len());
    let mut stride = 1;
    for &d in shape {
        strides.push(stride);
        stride *= d;
    }
    let mut index = vec![0usize; shape.len()];
    let mut out = Vec::with_capacity(data.len());
    for _ in 0..data.len() {
        out.push(
            data[index
                .iter()
                .zip(&strides)
                .map(|(i, s)| i * s)
                .sum::<usize>()],
        );
        // Next C-order index: the last axis fastest.
        for axis in (0..shape.len()).rev() {
            index[axis] += 1;
            if index[axis] < shape[axis] {
                break;
            }
            index[axis] = 0;
        }
    }
    out
}
