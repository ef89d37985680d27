//! Parquet output of a [`Table`] (cargo feature `parquet`, arrow-rs `parquet` crate), and
//! measured time histories read from Parquet ([`read_records`]).
//!
//! Types: `U64` → `uint64` (not null), `F64` → `double` (nullable: a metric not defined for a
//! row is null, a failed row NaN, as the CSV's empty field and `NaN`), `Str` → `utf8`
//! (nullable). Each field's Arrow metadata holds `unit` (SI, `"1"` for ratios and counts);
//! the table's metadata is both the Arrow schema metadata (pyarrow: `table.schema.metadata`)
//! and the Parquet file's key-value metadata (`pyarrow.parquet.read_metadata(p).metadata`).
//! Snappy compression, one row group per 65 536 rows. Written through [`AtomicFile`]: an
//! interrupted write leaves no file.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use arrow_array::{ArrayRef, Float64Array, RecordBatch, StringArray, UInt64Array};
use arrow_schema::{DataType, Field, Schema};
use parquet::arrow::ArrowWriter;
use parquet::basic::Compression;
use parquet::file::metadata::KeyValue;
use parquet::file::properties::WriterProperties;

use super::table::{ColumnData, Table};
use super::AtomicFile;
use crate::{Error, Result};

/// Rows per row group (and per record batch handed to the writer).
const ROW_GROUP_ROWS: usize = 65_536;

/// The Arrow schema of `table` (types, units, table metadata), checked: columns of equal
/// length, distinct names.
fn schema(table: &Table, path: &Path) -> Result<Schema> {
    let rows = table.rows();
    let mut fields = Vec::with_capacity(table.columns.len());
    for (k, c) in table.columns.iter().enumerate() {
        if c.data.len() != rows {
            return Err(Error::numerical(
                "parquet",
                format!(
                    "{}: column '{}' has {} rows, the first column {rows}",
                    path.display(),
                    c.name,
                    c.data.len()
                ),
            ));
        }
        if table.columns[..k].iter().any(|o| o.name == c.name) {
            return Err(Error::numerical(
                "parquet",
                format!("{}: column '{}' is given twice", path.display(), c.name),
            ));
        }
        let (ty, nullable) = match c.data {
            ColumnData::U64(_) => (DataType::UInt64, false),
            ColumnData::F64(_) => (DataType::Float64, true),
            ColumnData::Str(_) => (DataType::Utf8, true),
        };
        let mut f = Field::new(&c.name, ty, nullable);
        if let Some(u) = &c.unit {
            f = f.with_metadata(HashMap::from([("unit".to_string(), u.clone())]));
        }
        fields.push(f);
    }
    Ok(Schema::new_with_metadata(
        fields,
        table
            .metadata
            .iter()
            .cloned()
            .collect::<HashMap<String, String>>(),
    ))
}

/// Rows `a..b` of a column as an Arrow array.
fn slice(data: &ColumnData, a: usize, b: usize) -> ArrayRef {
    match data {
        ColumnData::U64(v) => Arc::new(UInt64Array::from(v[a..b].to_vec())),
        ColumnData::F64(v) => Arc::new(Float64Array::from(v[a..b].to_vec())),
        ColumnData::Str(v) => Arc::new(StringArray::from(v[a..b].to_vec())),
    }
}

/// Writes `table` to `path` as Parquet, atomically (see the module docs).
pub fn write_parquet(path: &Path, table: &Table) -> Result<()> {
    let err = |e: &dyn std::fmt::Display| {
        Error::io(
            path,
            std::io::Error::other(format!("cannot write Parquet: {e}")),
        )
    };
    let schema = Arc::new(schema(table, path)?);
    let props = WriterProperties::builder()
        .set_compression(Compression::SNAPPY)
        .set_max_row_group_row_count(Some(ROW_GROUP_ROWS))
        .set_key_value_metadata(Some(
            table
                .metadata
                .iter()
                .map(|(k, v)| KeyValue::new(k.clone(), v.clone()))
                .collect(),
        ))
        .build();
    let file = AtomicFile::create(path)?;
    let mut w = ArrowWriter::try_new(file, schema.clone(), Some(props)).map_err(|e| err(&e))?;
    let rows = table.rows();
    let mut a = 0;
    loop {
        let b = (a + ROW_GROUP_ROWS).min(rows);
        let arrays: Vec<ArrayRef> = table.columns.iter().map(|c| slice(&c.data, a, b)).collect();
        let batch = RecordBatch::try_new(schema.clone(), arrays).map_err(|e| err(&e))?;
        w.write(&batch).map_err(|e| err(&e))?;
        a = b;
        if a >= rows {
            break;
        }
    }
    let file = w.into_inner().map_err(|e| err(&e))?;
    file.commit()
}

// ------------------------------------------------------------------------------- reading

/// The values of a numeric Arrow column as `f64` (`None`: null), or `None` when the column is
/// not numeric.
fn numbers(a: &dyn arrow_array::Array) -> Option<Vec<Option<f64>>> {
    use arrow_array::cast::AsArray;
    use arrow_array::types::*;
    macro_rules! prim {
        ($t:ty) => {
            a.as_primitive_opt::<$t>()
                .map(|p| p.iter().map(|v| v.map(|x| x as f64)).collect())
        };
    }
    match a.data_type() {
        DataType::Float64 => prim!(Float64Type),
        DataType::Float32 => prim!(Float32Type),
        DataType::Int64 => prim!(Int64Type),
        DataType::Int32 => prim!(Int32Type),
        DataType::Int16 => prim!(Int16Type),
        DataType::Int8 => prim!(Int8Type),
        DataType::UInt64 => prim!(UInt64Type),
        DataType::UInt32 => prim!(UInt32Type),
        DataType::UInt16 => prim!(UInt16Type),
        DataType::UInt8 => prim!(UInt8Type),
        _ => None,
    }
}

/// Measured time histories in Parquet: the columns of a CSV file
/// ([`crate::io::csv_records`]: `NAME_UNIT` names, one time column, `_j` energies passed
/// over), of any numeric type (double, float, integers; converted to `f64`). A column of
/// another type, a null, a non-finite value or one that overflows in SI is refused naming the
/// file, the column and the row (counted from 1 over the whole file).
pub fn read_records(path: &Path) -> Result<Vec<crate::record::Record>> {
    use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
    let file = path.display().to_string();
    let bad = |message: String| Error::Input {
        location: file.clone(),
        message,
    };
    let (f, _) = crate::input::open(path)?;
    let builder = ParquetRecordBatchReaderBuilder::try_new(f)
        .map_err(|e| bad(format!("not a Parquet file meid can read: {e}")))?;
    let names: Vec<String> = builder
        .schema()
        .fields()
        .iter()
        .map(|f| f.name().clone())
        .collect();
    let (cols, tc) = crate::io::csv_records::column_kinds(&names).map_err(&bad)?;
    let rows = builder.metadata().file_metadata().num_rows().max(0) as usize;
    let mut data: Vec<Vec<f64>> = cols
        .iter()
        .map(|c| {
            if c.is_some() {
                Vec::with_capacity(rows)
            } else {
                Vec::new()
            }
        })
        .collect();
    let reader = builder
        .build()
        .map_err(|e| bad(format!("cannot read the Parquet data: {e}")))?;
    let mut row0 = 0usize;
    for batch in reader {
        let batch = batch.map_err(|e| bad(format!("cannot read the Parquet data: {e}")))?;
        for (k, c) in cols.iter().enumerate() {
            let Some((name, _, factor)) = c else { continue };
            let column = batch.column(k);
            let Some(v) = numbers(column.as_ref()) else {
                return Err(bad(format!(
                    "column {} '{}': type {}, expected numbers (double, float or integers)",
                    k + 1,
                    names[k],
                    column.data_type()
                )));
            };
            for (i, x) in v.into_iter().enumerate() {
                let row = row0 + i + 1;
                let Some(x) = x else {
                    return Err(bad(format!(
                        "column {} ({name}), row {row}: null, expected a number",
                        k + 1
                    )));
                };
                let si = x * factor;
                if !si.is_finite() {
                    return Err(bad(format!(
                        "column {} ({name}), row {row}: {x} is not a finite number in SI (× {factor})",
                        k + 1
                    )));
                }
                data[k].push(si);
            }
        }
        row0 += batch.num_rows();
    }
    let origin = |k: usize| format!("{file}, column {}", k + 1);
    crate::io::csv_records::records_from_columns(&names, cols, data, tc, &origin).map_err(bad)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::table::Column;
    use arrow_array::Array;
    use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;

    fn table(rows: usize) -> Table {
        Table {
            columns: vec![
                Column {
                    name: "index".into(),
                    unit: Some("1".into()),
                    data: ColumnData::U64((0..rows as u64).collect()),
                },
                Column {
                    name: "peak_floor_force_n".into(),
                    unit: Some("N".into()),
                    data: ColumnData::F64(
                        (0..rows)
                            .map(|i| match i % 3 {
                                0 => Some(i as f64 * 0.1),
                                1 => None,
                                _ => Some(f64::NAN),
                            })
                            .collect(),
                    ),
                },
                Column {
                    name: "error".into(),
                    unit: None,
                    data: ColumnData::Str(
                        (0..rows)
                            .map(|i| (i % 3 == 2).then(|| format!("point {i}: \"failed\", again")))
                            .collect(),
                    ),
                },
            ],
            metadata: vec![("seed".into(), "42".into())],
        }
    }

    /// Measured records from Parquet: the CSV's column names, integer and double columns,
    /// units converted to SI; a null, a text column or a file that is not Parquet refused
    /// naming the file, column and row (session 12: `meid measure x.parquet` was read as UFF,
    /// "expected the start of a dataset").
    #[test]
    fn measured_records_read_from_parquet() {
        let dir = std::env::temp_dir().join(format!("meid-parquet-rec-{}", std::process::id()));
        let path = dir.join("lab.parquet");
        let col = |name: &str, data: ColumnData| Column {
            name: name.into(),
            unit: None,
            data,
        };
        let rows = 70_000; // more than a row group
        let accel = |i: usize| (i as f64 * 0.01).sin();
        let mut t = Table {
            columns: vec![
                col(
                    "time_us",
                    ColumnData::U64((0..rows as u64).map(|i| 100 * i).collect()),
                ),
                col(
                    "accel_B_g",
                    ColumnData::F64((0..rows).map(|i| Some(accel(i))).collect()),
                ),
                col("ke_slider_j", ColumnData::F64(vec![Some(1.0); rows])),
                col(
                    "force_floor_kn",
                    ColumnData::F64((0..rows).map(|i| Some(i as f64)).collect()),
                ),
            ],
            metadata: Vec::new(),
        };
        write_parquet(&path, &t).unwrap();
        let r = read_records(&path).unwrap();
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].name, "accel_B");
        assert_eq!(r[0].quantity, crate::record::Quantity::Acceleration);
        assert_eq!(r[0].values[rows - 1], accel(rows - 1) * 9.80665);
        assert_eq!(r[1].values[rows - 1], (rows - 1) as f64 * 1e3);
        assert_eq!(r[1].origin, format!("{}, column 4", path.display()));
        let (t0, dt) = r[0].even().unwrap();
        assert_eq!(t0, 0.0);
        assert!((dt - 1e-4).abs() < 1e-16, "{dt}");
        // A null in row 65 540 (the second row group).
        if let ColumnData::F64(v) = &mut t.columns[1].data {
            v[65_539] = None;
        }
        write_parquet(&path, &t).unwrap();
        let e = read_records(&path).unwrap_err().to_string();
        assert!(
            e.contains("lab.parquet: column 2 (accel_B), row 65540: null"),
            "{e}"
        );
        t.columns[1] = col("accel_B_g", ColumnData::Str(vec![Some("1".into()); rows]));
        write_parquet(&path, &t).unwrap();
        let e = read_records(&path).unwrap_err().to_string();
        assert!(
            e.contains("column 2 'accel_B_g': type Utf8, expected numbers"),
            "{e}"
        );
        t.columns[1] = col("accel_B", ColumnData::F64(vec![Some(1.0); rows]));
        write_parquet(&path, &t).unwrap();
        let e = read_records(&path).unwrap_err().to_string();
        assert!(
            e.contains("column 2 'accel_B': the name does not end in a unit"),
            "{e}"
        );
        std::fs::write(&path, "time_s,accel_B_g\n0,1\n").unwrap();
        let e = read_records(&path).unwrap_err().to_string();
        assert!(e.contains("lab.parquet: not a Parquet file"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn round_trip_types_units_nulls_and_metadata() {
        let dir = std::env::temp_dir().join(format!("meid-parquet-{}", std::process::id()));
        let path = dir.join("t.parquet");
        // More rows than a row group: the batches are cut and put together again.
        let rows = ROW_GROUP_ROWS + 7;
        let t = table(rows);
        write_parquet(&path, &t).unwrap();
        let file = std::fs::File::open(&path).unwrap();
        let b = ParquetRecordBatchReaderBuilder::try_new(file).unwrap();
        let kv = b.metadata().file_metadata().key_value_metadata().unwrap();
        assert!(kv
            .iter()
            .any(|k| k.key == "seed" && k.value.as_deref() == Some("42")));
        assert_eq!(b.metadata().num_row_groups(), 2);
        let schema = b.schema().clone();
        assert_eq!(
            schema.metadata().get("seed").map(String::as_str),
            Some("42")
        );
        assert_eq!(schema.field(0).data_type(), &DataType::UInt64);
        assert_eq!(schema.field(1).data_type(), &DataType::Float64);
        assert_eq!(schema.field(2).data_type(), &DataType::Utf8);
        assert_eq!(
            schema.field(1).metadata().get("unit").map(String::as_str),
            Some("N")
        );
        assert!(schema.field(2).metadata().is_empty());
        let mut seen = 0;
        for batch in b.build().unwrap() {
            let batch = batch.unwrap();
            let idx = batch
                .column(0)
                .as_any()
                .downcast_ref::<UInt64Array>()
                .unwrap();
            let f = batch
                .column(1)
                .as_any()
                .downcast_ref::<Float64Array>()
                .unwrap();
            let e = batch
                .column(2)
                .as_any()
                .downcast_ref::<StringArray>()
                .unwrap();
            for r in 0..batch.num_rows() {
                let i = seen + r;
                assert_eq!(idx.value(r), i as u64);
                match i % 3 {
                    0 => assert_eq!(f.value(r).to_bits(), (i as f64 * 0.1).to_bits()),
                    1 => assert!(f.is_null(r)),
                    _ => assert!(f.is_valid(r) && f.value(r).is_nan()),
                }
                if i % 3 == 2 {
                    assert_eq!(e.value(r), format!("point {i}: \"failed\", again"));
                } else {
                    assert!(e.is_null(r));
                }
            }
            seen += batch.num_rows();
        }
        assert_eq!(seen, rows);
        // No temporary is left beside the file.
        let names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .collect();
        assert_eq!(names, vec!["t.parquet".to_string()]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn ragged_columns_are_refused_and_leave_no_file() {
        let dir = std::env::temp_dir().join(format!("meid-parquet-bad-{}", std::process::id()));
        let path = dir.join("t.parquet");
        let mut t = table(5);
        t.columns[1].data = ColumnData::F64(vec![Some(1.0)]);
        let e = write_parquet(&path, &t).unwrap_err().to_string();
        assert!(e.contains("'peak_floor_force_n' has 1 rows"), "{e}");
        assert!(!path.exists());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
