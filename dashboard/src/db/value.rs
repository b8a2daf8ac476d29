//! Values bound to and read from statements, the same on both backends.
//!
//! Integers are 64-bit (`BIGINT`), reals 64-bit (`DOUBLE PRECISION` / `REAL`), booleans are stored
//! as integers 0 and 1. Not for: conversions from record types (that is [`crate::store`]).

use super::DbError;

#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Null,
    Int(i64),
    Real(f64),
    Text(String),
    Blob(Vec<u8>),
}

impl From<i64> for Value {
    fn from(v: i64) -> Self {
        Value::Int(v)
    }
}
impl From<bool> for Value {
    fn from(v: bool) -> Self {
        Value::Int(v as i64)
    }
}
impl From<f64> for Value {
    /// Non-finite reals are stored as NULL: neither backend's JSON nor SQL treats them alike.
    fn from(v: f64) -> Self {
        if v.is_finite() {
            Value::Real(v)
        } else {
            Value::Null
        }
    }
}
impl From<&str> for Value {
    fn from(v: &str) -> Self {
        Value::Text(v.to_string())
    }
}
impl From<String> for Value {
    fn from(v: String) -> Self {
        Value::Text(v)
    }
}
impl From<&String> for Value {
    fn from(v: &String) -> Self {
        Value::Text(v.clone())
    }
}
impl From<Vec<u8>> for Value {
    fn from(v: Vec<u8>) -> Self {
        Value::Blob(v)
    }
}
impl<T: Into<Value>> From<Option<T>> for Value {
    fn from(v: Option<T>) -> Self {
        v.map_or(Value::Null, Into::into)
    }
}

/// One result row.
#[derive(Clone, Debug, PartialEq)]
pub struct Row(pub Vec<Value>);

impl Row {
    fn get(&self, i: usize) -> Result<&Value, DbError> {
        self.0.get(i).ok_or_else(|| DbError::Column {
            column: i,
            detail: format!("the row has {} columns", self.0.len()),
        })
    }

    fn mismatch(&self, i: usize, want: &str) -> DbError {
        DbError::Column {
            column: i,
            detail: format!("wanted {want}, found {:?}", self.0.get(i)),
        }
    }

    pub fn i64(&self, i: usize) -> Result<i64, DbError> {
        match self.get(i)? {
            Value::Int(v) => Ok(*v),
            Value::Real(v) if v.fract() == 0.0 => Ok(*v as i64),
            _ => Err(self.mismatch(i, "an integer")),
        }
    }

    pub fn opt_i64(&self, i: usize) -> Result<Option<i64>, DbError> {
        match self.get(i)? {
            Value::Null => Ok(None),
            _ => self.i64(i).map(Some),
        }
    }

    pub fn f64(&self, i: usize) -> Result<f64, DbError> {
        match self.get(i)? {
            Value::Real(v) => Ok(*v),
            Value::Int(v) => Ok(*v as f64),
            _ => Err(self.mismatch(i, "a real")),
        }
    }

    pub fn opt_f64(&self, i: usize) -> Result<Option<f64>, DbError> {
        match self.get(i)? {
            Value::Null => Ok(None),
            _ => self.f64(i).map(Some),
        }
    }

    pub fn bool(&self, i: usize) -> Result<bool, DbError> {
        Ok(self.i64(i)? != 0)
    }

    pub fn str(&self, i: usize) -> Result<&str, DbError> {
        match self.get(i)? {
            Value::Text(v) => Ok(v),
            _ => Err(self.mismatch(i, "text")),
        }
    }

    pub fn string(&self, i: usize) -> Result<String, DbError> {
        self.str(i).map(str::to_string)
    }

    pub fn opt_string(&self, i: usize) -> Result<Option<String>, DbError> {
        match self.get(i)? {
            Value::Null => Ok(None),
            _ => self.string(i).map(Some),
        }
    }

    pub fn blob(&self, i: usize) -> Result<&[u8], DbError> {
        match self.get(i)? {
            Value::Blob(v) => Ok(v),
            _ => Err(self.mismatch(i, "a blob")),
        }
    }

    pub fn opt_blob(&self, i: usize) -> Result<Option<&[u8]>, DbError> {
        match self.get(i)? {
            Value::Null => Ok(None),
            _ => self.blob(i).map(Some),
        }
    }
}
