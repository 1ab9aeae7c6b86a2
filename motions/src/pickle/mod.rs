//! A Python pickle reader that runs no code: NumPy arrays, dicts, lists, tuples, strings and
//! numbers, as 4D-Dress and similar captures store SMPL fits and meshes.
//!
//! Unpickling in Python calls whatever functions the file names, so a pickle from elsewhere
//! is a program. This reader is a pickle machine whose only callables are an allow-list
//! ([`ALLOWED`]): NumPy's array and dtype reconstructors and `_codecs.encode` (how protocol 2
//! stores bytes). A file that calls anything else (`os.system`, a PyTorch rebuild function, a
//! class of its own) is refused naming the callable, before anything of it is used. Written
//! here because no maintained crate reads NumPy arrays out of a pickle: `serde-pickle` has no
//! way to evaluate NumPy's reconstructors, and the scrapers that do are unmaintained drafts.
//!
//! Opcodes of protocols 2 to 5 (and the text forms of 0 and 1 that such files still use) are
//! read; lengths are checked against the bytes left, nesting is bounded, so a damaged or
//! hostile file is an error and never a large allocation.

use std::collections::HashMap;

mod numpy;
#[cfg(test)]
mod tests;

pub use numpy::{Array, Dtype};
use numpy::{array_state, dtype, from_buffer, scalar};

/// The callables a pickle may invoke: (module, name). NumPy 1 (`numpy.core`) and NumPy 2
/// (`numpy._core`) spell the first two differently.
pub const ALLOWED: [(&str, &str); 9] = [
    ("numpy.core.multiarray", "_reconstruct"),
    ("numpy._core.multiarray", "_reconstruct"),
    ("numpy.core.numeric", "_frombuffer"),
    ("numpy._core.numeric", "_frombuffer"),
    ("numpy.core.multiarray", "scalar"),
    ("numpy._core.multiarray", "scalar"),
    ("numpy", "dtype"),
    ("numpy", "ndarray"),
    ("_codecs", "encode"),
];

/// Deepest nesting of containers accepted when values are read out.
const MAX_DEPTH: usize = 64;

/// Most lists, tuples and dicts one file may make (each NumPy array takes about four tuples):
/// bounds the nesting a hostile file can build before it is read out.
const MAX_CONTAINERS: usize = 4096;

/// A value read from a pickle.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// `None`.
    None,
    /// A boolean.
    Bool(bool),
    /// An integer that fits 64 bits.
    Int(i64),
    /// A float.
    Float(f64),
    /// A string.
    Str(String),
    /// Bytes (or a bytearray).
    Bytes(Vec<u8>),
    /// A list.
    List(Vec<Value>),
    /// A tuple.
    Tuple(Vec<Value>),
    /// A dict, in the file's order.
    Dict(Vec<(Value, Value)>),
    /// A NumPy array, its values as f64, in C order.
    Array(Array),
    /// A NumPy dtype.
    Dtype(Dtype),
    /// A module attribute named by the file (a class or function it did not call).
    Global(String, String),
}

impl Value {
    /// The value under `key` of a dict with string keys.
    pub fn get(&self, key: &str) -> Option<&Value> {
        match self {
            Value::Dict(items) => items
                .iter()
                .find(|(k, _)| matches!(k, Value::Str(s) if s == key))
                .map(|(_, v)| v),
            _ => None,
        }
    }
}

/// Reads the pickle in `bytes`. The error says what is wrong and at which byte.
pub fn read(bytes: &[u8]) -> Result<Value, String> {
    let mut machine = Machine {
        input: bytes,
        at: 0,
        stack: Vec::new(),
        marks: Vec::new(),
        memo: HashMap::new(),
        objects: Vec::new(),
        containers: 0,
    };
    let top = machine.run()?;
    machine.resolve(top, 0)
}

/// A value on the machine's stack: plain, or an object others may share and BUILD may change.
#[derive(Debug, Clone)]
enum Slot {
    Plain(Value),
    Object(usize),
    /// A list, tuple or dict whose items are slots (built by the container opcodes).
    List(Vec<Slot>),
    Tuple(Vec<Slot>),
    Dict(Vec<(Slot, Slot)>),
}

/// An object under construction.
#[derive(Debug, Clone)]
enum Object {
    Done(Slot),
    /// `_reconstruct(ndarray, ...)`: an empty array waiting for its BUILD state.
    EmptyArray,
}

struct Machine<'a> {
    input: &'a [u8],
    at: usize,
    stack: Vec<Slot>,
    marks: Vec<usize>,
    memo: HashMap<u64, Slot>,
    objects: Vec<Object>,
    containers: usize,
}

impl Machine<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        if n > self.input.len() - self.at {
            return Err(format!(
                "byte {}: {n} bytes announced, {} left (the file is cut short or damaged)",
                self.at,
                self.input.len() - self.at
            ));
        }
        let bytes = &self.input[self.at..self.at + n];
        self.at += n;
        Ok(bytes)
    }

    fn uint(&mut self, n: usize) -> Result<u64, String> {
        let bytes = self.take(n)?;
        Ok(bytes
            .iter()
            .rev()
            .fold(0u64, |acc, &b| (acc << 8) | u64::from(b)))
    }

    fn line(&mut self) -> Result<String, String> {
        let rest = &self.input[self.at..];
        let end = rest
            .iter()
            .position(|&b| b == b'\n')
            .ok_or_else(|| format!("byte {}: a text argument without its newline", self.at))?;
        let text = String::from_utf8_lossy(&rest[..end]).into_owned();
        self.at += end + 1;
        Ok(text)
    }

    fn pop(&mut self) -> Result<Slot, String> {
        self.stack
            .pop()
            .ok_or_else(|| format!("byte {}: the stack is empty", self.at))
    }

    fn pop_mark(&mut self) -> Result<Vec<Slot>, String> {
        let mark = self
            .marks
            .pop()
            .ok_or_else(|| format!("byte {}: no MARK to pop to", self.at))?;
        if mark > self.stack.len() {
            return Err(format!("byte {}: a MARK past the stack", self.at));
        }
        Ok(self.stack.split_off(mark))
    }

    /// Pushes a new list, tuple or dict, counting it against [`MAX_CONTAINERS`].
    fn push_container(&mut self, slot: Slot) -> Result<(), String> {
        self.containers += 1;
        if self.containers > MAX_CONTAINERS {
            return Err(format!(
                "byte {}: more than {MAX_CONTAINERS} lists, tuples and dicts (not a file of \
                 arrays)",
                self.at
            ));
        }
        self.stack.push(slot);
        Ok(())
    }

    fn push(&mut self, value: Value) {
        self.stack.push(Slot::Plain(value));
    }

    fn string(&mut self, n: usize) -> Result<(), String> {
        let bytes = self.take(n)?.to_vec();
        let text = String::from_utf8(bytes).map_err(|_| format!("byte {}: not UTF-8", self.at))?;
        self.push(Value::Str(text));
        Ok(())
    }

    fn bytes(&mut self, n: usize) -> Result<(), String> {
        let bytes = self.take(n)?.to_vec();
        self.push(Value::Bytes(bytes));
        Ok(())
    }

    fn length(&mut self, width: usize) -> Result<usize, String> {
        let n = self.uint(width)?;
        usize::try_from(n).map_err(|_| format!("byte {}: length {n} does not fit", self.at))
    }

    /// Runs to STOP and returns the top of the stack.
    fn run(&mut self) -> Result<Slot, String> {
        loop {
            let op = *self.take(1)?.first().expect("one byte taken");
            if op == b'.' {
                return self.pop();
            }
            self.step(op)?;
        }
    }

    fn step(&mut self, op: u8) -> Result<(), String> {
        match op {
            // PROTO, FRAME: sizes only.
            0x80 => {
                self.take(1)?;
            }
            0x95 => {
                self.take(8)?;
            }
            b'(' => self.marks.push(self.stack.len()), // MARK
            b'0' => {
                self.pop()?; // POP
            }
            b'1' => {
                self.pop_mark()?; // POP_MARK
            }
            b'2' => {
                let top = self.pop()?; // DUP
                self.stack.push(top.clone());
                self.stack.push(top);
            }
            b'N' => self.push(Value::None),
            0x88 => self.push(Value::Bool(true)),
            0x89 => self.push(Value::Bool(false)),
            b'K' => {
                let v = self.uint(1)? as i64;
                self.push(Value::Int(v));
            }
            b'M' => {
                let v = self.uint(2)? as i64;
                self.push(Value::Int(v));
            }
            b'J' => {
                let v = self.uint(4)? as u32 as i32;
                self.push(Value::Int(i64::from(v)));
            }
            0x8a => {
                let n = self.length(1)?; // LONG1
                self.long(n)?;
            }
            b'G' => {
                let bits = self.take(8)?.try_into().expect("eight bytes");
                self.push(Value::Float(f64::from_be_bytes(bits)));
            }
            b'I' | b'L' | b'F' => self.text_number(op)?,
            // STRING (a quoted repr) and UNICODE (raw text): protocol 0's strings.
            b'S' | b'V' => {
                let line = self.line()?;
                let text = match (op, line.as_bytes()) {
                    (b'S', [q @ (b'\'' | b'"'), .., last]) if last == q => {
                        line[1..line.len() - 1].to_string()
                    }
                    (b'S', _) => return Err(format!("byte {}: an unquoted STRING", self.at)),
                    _ => line,
                };
                self.push(Value::Str(text));
            }
            0x8c | b'U' => {
                let n = self.length(1)?;
                self.string(n)?;
            }
            b'X' | b'T' => {
                let n = self.length(4)?;
                self.string(n)?;
            }
            0x8d => {
                let n = self.length(8)?;
                self.string(n)?;
            }
            b'C' => {
                let n = self.length(1)?;
                self.bytes(n)?;
            }
            b'B' => {
                let n = self.length(4)?;
                self.bytes(n)?;
            }
            0x8e | 0x96 => {
                let n = self.length(8)?;
                self.bytes(n)?;
            }
            _ => self.step_structure(op)?,
        }
        Ok(())
    }

    fn step_structure(&mut self, op: u8) -> Result<(), String> {
        match op {
            b'}' => self.push_container(Slot::Dict(Vec::new()))?,
            b']' => self.push_container(Slot::List(Vec::new()))?,
            b')' => self.push_container(Slot::Tuple(Vec::new()))?,
            b'd' => {
                let items = self.pop_mark()?;
                let items = pairs(items, self.at)?;
                self.push_container(Slot::Dict(items))?;
            }
            b'l' => {
                let items = self.pop_mark()?;
                self.push_container(Slot::List(items))?;
            }
            b't' => {
                let items = self.pop_mark()?;
                self.push_container(Slot::Tuple(items))?;
            }
            0x85..=0x87 => {
                let n = usize::from(op - 0x84);
                if self.stack.len() < n {
                    return Err(format!(
                        "byte {}: a tuple of {n} from a shorter stack",
                        self.at
                    ));
                }
                let items = self.stack.split_off(self.stack.len() - n);
                self.push_container(Slot::Tuple(items))?;
            }
            b'a' => {
                let item = self.pop()?;
                self.extend_list(vec![item])?;
            }
            b'e' => {
                let items = self.pop_mark()?;
                self.extend_list(items)?;
            }
            b's' => {
                let value = self.pop()?;
                let key = self.pop()?;
                self.extend_dict(vec![(key, value)])?;
            }
            b'u' => {
                let items = self.pop_mark()?;
                let items = pairs(items, self.at)?;
                self.extend_dict(items)?;
            }
            _ => self.step_memo_and_calls(op)?,
        }
        Ok(())
    }

    fn step_memo_and_calls(&mut self, op: u8) -> Result<(), String> {
        match op {
            b'q' => {
                let k = self.uint(1)?;
                self.memoize(k)?;
            }
            b'r' => {
                let k = self.uint(4)?;
                self.memoize(k)?;
            }
            0x94 => {
                let k = self.memo.len() as u64;
                self.memoize(k)?;
            }
            b'p' => {
                let k = self.line()?.trim().parse().map_err(|_| bad_text(self.at))?;
                self.memoize(k)?;
            }
            b'h' | b'j' | b'g' => {
                let k = match op {
                    b'h' => self.uint(1)?,
                    b'j' => self.uint(4)?,
                    _ => self.line()?.trim().parse().map_err(|_| bad_text(self.at))?,
                };
                let slot = self.memo.get(&k).cloned().ok_or_else(|| {
                    format!(
                        "byte {}: memo entry {k} read before it was written",
                        self.at
                    )
                })?;
                self.stack.push(slot);
            }
            b'c' => {
                let module = self.line()?;
                let name = self.line()?;
                self.push(Value::Global(module, name));
            }
            0x93 => {
                let name = self.pop()?;
                let module = self.pop()?;
                match (module, name) {
                    (Slot::Plain(Value::Str(m)), Slot::Plain(Value::Str(n))) => {
                        self.push(Value::Global(m, n))
                    }
                    _ => return Err(format!("byte {}: STACK_GLOBAL of non-strings", self.at)),
                }
            }
            b'R' | 0x81 => {
                let args = self.pop()?;
                let callable = self.pop()?;
                let made = self.call(callable, args)?;
                self.stack.push(made);
            }
            b'b' => {
                let state = self.pop()?;
                let target = self.pop()?;
                let built = self.build(target, state)?;
                self.stack.push(built);
            }
            other => {
                return Err(format!(
                    "byte {}: opcode 0x{other:02x} is not read here (an extension, a persistent \
                     id or an object of a class: not plain data)",
                    self.at - 1
                ));
            }
        }
        Ok(())
    }

    /// Gives the top of the stack a memo entry: containers and objects become shared objects,
    /// so that what is appended or built later is seen through every reference.
    fn memoize(&mut self, k: u64) -> Result<(), String> {
        let top = self.pop()?;
        let slot = match top {
            Slot::Object(_) | Slot::Plain(_) => top,
            container => {
                self.objects.push(Object::Done(container));
                Slot::Object(self.objects.len() - 1)
            }
        };
        self.memo.insert(k, slot.clone());
        self.stack.push(slot);
        Ok(())
    }

    fn extend_list(&mut self, items: Vec<Slot>) -> Result<(), String> {
        let at = self.at;
        match self.top_container()? {
            Slot::List(list) => list.extend(items),
            _ => return Err(format!("byte {at}: APPEND to something not a list")),
        }
        Ok(())
    }

    fn extend_dict(&mut self, items: Vec<(Slot, Slot)>) -> Result<(), String> {
        let at = self.at;
        match self.top_container()? {
            Slot::Dict(dict) => dict.extend(items),
            _ => return Err(format!("byte {at}: SETITEM on something not a dict")),
        }
        Ok(())
    }

    /// The container on top of the stack (through its shared object, if it has one).
    fn top_container(&mut self) -> Result<&mut Slot, String> {
        let at = self.at;
        match self.stack.last_mut() {
            Some(Slot::Object(id)) => match &mut self.objects[*id] {
                Object::Done(slot) => Ok(slot),
                Object::EmptyArray => Err(format!("byte {at}: items added to an array")),
            },
            Some(slot) => Ok(slot),
            None => Err(format!("byte {at}: the stack is empty")),
        }
    }

    /// REDUCE: only the allow-listed callables, evaluated here.
    fn call(&mut self, callable: Slot, args: Slot) -> Result<Slot, String> {
        let (module, name) = match self.resolve(callable, 0)? {
            Value::Global(m, n) => (m, n),
            other => return Err(format!("byte {}: a call of {other:?}", self.at)),
        };
        if !ALLOWED.contains(&(module.as_str(), name.as_str())) {
            return Err(format!(
                "it calls {module}.{name}, which this reader does not run (it runs no code from \
                 a file: only NumPy arrays and plain data are read)"
            ));
        }
        let args = match self.resolve(args, 0)? {
            Value::Tuple(args) => args,
            other => return Err(format!("{module}.{name} called with {other:?}")),
        };
        let value = match (module.as_str(), name.as_str()) {
            (_, "_reconstruct") => {
                self.objects.push(Object::EmptyArray);
                return Ok(Slot::Object(self.objects.len() - 1));
            }
            (_, "_frombuffer") => from_buffer(&args)?,
            (_, "scalar") => scalar(&args)?,
            (_, "dtype") => Value::Dtype(dtype(args.first())?),
            ("_codecs", _) => match args.as_slice() {
                [Value::Str(text), ..] => Value::Bytes(text.chars().map(|c| c as u8).collect()),
                _ => return Err("_codecs.encode without a string".into()),
            },
            _ => return Err(format!("{module}.{name} is not called by NumPy's pickles")),
        };
        self.objects.push(Object::Done(Slot::Plain(value)));
        Ok(Slot::Object(self.objects.len() - 1))
    }

    /// BUILD: a NumPy array's or dtype's state; anything else is refused.
    fn build(&mut self, target: Slot, state: Slot) -> Result<Slot, String> {
        let Slot::Object(id) = target else {
            return Err(format!("byte {}: BUILD on plain data", self.at));
        };
        let state = self.resolve(state, 0)?;
        let built = match &self.objects[id] {
            Object::EmptyArray => Value::Array(array_state(&state)?),
            Object::Done(Slot::Plain(Value::Dtype(d))) => {
                let mut d = *d;
                if let Value::Tuple(items) = &state
                    && let Some(Value::Str(order)) = items.get(1)
                {
                    d.big_endian = order == ">";
                }
                Value::Dtype(d)
            }
            other => return Err(format!("byte {}: BUILD on {other:?}", self.at)),
        };
        self.objects[id] = Object::Done(Slot::Plain(built));
        Ok(Slot::Object(id))
    }

    /// The plain value of a slot (shared objects copied out).
    fn resolve(&self, slot: Slot, depth: usize) -> Result<Value, String> {
        if depth > MAX_DEPTH {
            return Err(format!("nested deeper than {MAX_DEPTH} levels"));
        }
        let all = |items: Vec<Slot>| {
            items
                .into_iter()
                .map(|s| self.resolve(s, depth + 1))
                .collect::<Result<Vec<_>, _>>()
        };
        Ok(match slot {
            Slot::Plain(v) => v,
            Slot::List(items) => Value::List(all(items)?),
            Slot::Tuple(items) => Value::Tuple(all(items)?),
            Slot::Dict(items) => Value::Dict(
                items
                    .into_iter()
                    .map(|(k, v)| Ok((self.resolve(k, depth + 1)?, self.resolve(v, depth + 1)?)))
                    .collect::<Result<_, String>>()?,
            ),
            Slot::Object(id) => match &self.objects[id] {
                Object::Done(inner) => self.resolve(inner.clone(), depth + 1)?,
                Object::EmptyArray => return Err("an array without its data (no BUILD)".into()),
            },
        })
    }

    fn long(&mut self, n: usize) -> Result<(), String> {
        let bytes = self.take(n)?;
        if n > 8 {
            return Err(format!("byte {}: an integer of {n} bytes", self.at));
        }
        let mut v: i64 = 0;
        for (i, &b) in bytes.iter().enumerate() {
            v |= i64::from(b) << (8 * i);
        }
        if n > 0 && n < 8 && bytes[n - 1] & 0x80 != 0 {
            v -= 1i64 << (8 * n);
        }
        self.push(Value::Int(v));
        Ok(())
    }

    fn text_number(&mut self, op: u8) -> Result<(), String> {
        let text = self.line()?;
        let text = text.trim().trim_end_matches('L');
        let value = match (op, text) {
            (b'I', "01") => Value::Bool(true),
            (b'I', "00") => Value::Bool(false),
            (b'F', t) => Value::Float(t.parse().map_err(|_| bad_text(self.at))?),
            (_, t) => Value::Int(t.parse().map_err(|_| bad_text(self.at))?),
        };
        self.push(value);
        Ok(())
    }
}

fn bad_text(at: usize) -> String {
    format!("byte {at}: a text number that does not parse")
}

fn pairs(items: Vec<Slot>, at: usize) -> Result<Vec<(Slot, Slot)>, String> {
    if !items.len().is_multiple_of(2) {
        return Err(format!("byte {at}: a dict of an odd number of items"));
    }
    let mut out = Vec::with_capacity(items.len() / 2);
    let mut items = items.into_iter();
    while let (Some(k), Some(v)) = (items.next(), items.next()) {
        out.push((k, v));
    }
    Ok(out)
}
