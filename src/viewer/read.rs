//! Reading `.rrd` recordings back (tests, `fitup view`): every logged component as a
//! flat row of numbers and texts.

use super::ViewerError;
use rerun::external::arrow::array::{
    Array, ArrayRef, FixedSizeListArray, Float32Array, Float64Array, Int64Array, ListArray,
    StringArray, StructArray, UInt32Array, UInt8Array,
};
use rerun::log::LogMsg;
use std::collections::HashMap;
use std::path::Path;

/// One logged component of one row of a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Which recording of the file (0 for the first one seen).
    pub recording: usize,
    /// The entity path's parts (`["cell", "plate_a"]`).
    pub entity: Vec<String>,
    /// The component (`Transform3D:translation`, `Scalars:scalars`…).
    pub component: String,
    /// The `step` timeline's value; `None` for static data or rows without it.
    pub step: Option<i64>,
    /// Every number of the component, flattened in order (positions x y z …).
    pub values: Vec<f64>,
    /// Every text of the component (labels, log lines).
    pub texts: Vec<String>,
}

impl Row {
    /// The entity path as `a/b/c`.
    pub fn entity_path(&self) -> String {
        self.entity.join("/")
    }
}

/// Calls `f` with every message of a recording file; returns how many.
pub(crate) fn for_each_message(
    file: &Path,
    mut f: impl FnMut(LogMsg),
) -> Result<usize, ViewerError> {
    let fail = |reason: String| ViewerError::Recording {
        path: file.to_path_buf(),
        reason,
    };
    let reader = std::fs::File::open(file).map_err(|e| fail(e.to_string()))?;
    let decoder =
        rerun::external::re_log_encoding::DecoderApp::decode_lazy(std::io::BufReader::new(reader));
    let mut n = 0;
    for msg in decoder {
        let msg = msg.map_err(|e| fail(format!("not a readable Rerun recording: {e}")))?;
        f(msg);
        n += 1;
    }
    if n == 0 {
        return Err(fail("empty: not a Rerun recording".into()));
    }
    Ok(n)
}

/// Reads every component row of a `.rrd` file.
///
/// # Errors
/// A file that cannot be read or is not a Rerun recording.
pub fn read_recording(file: &Path) -> Result<Vec<Row>, ViewerError> {
    let mut rows = Vec::new();
    let mut stores: HashMap<String, usize> = HashMap::new();
    let mut bad = None;
    for_each_message(file, |msg| {
        let LogMsg::ArrowMsg(store, arrow) = msg else {
            return;
        };
        let next = stores.len();
        let recording = *stores.entry(format!("{store:?}")).or_insert(next);
        let chunk = match rerun::log::Chunk::from_arrow_msg(&arrow) {
            Ok(c) => c,
            Err(e) => {
                bad = Some(e.to_string());
                return;
            }
        };
        let entity: Vec<String> = chunk
            .entity_path()
            .iter()
            .map(|p| p.unescaped_str().to_string())
            .collect();
        let steps = chunk
            .timelines()
            .iter()
            .find(|(name, _)| name.as_str() == super::backend::STEP)
            .map(|(_, col)| col.times_raw().to_vec());
        for column in chunk.components().0.values() {
            let list = &column.list_array;
            for row in 0..list.len() {
                if list.is_null(row) {
                    continue;
                }
                let mut values = Vec::new();
                let mut texts = Vec::new();
                flatten(&list.value(row), &mut values, &mut texts);
                rows.push(Row {
                    recording,
                    entity: entity.clone(),
                    component: column.descriptor.component.to_string(),
                    step: steps.as_ref().and_then(|s| s.get(row).copied()),
                    values,
                    texts,
                });
            }
        }
    })?;
    if let Some(reason) = bad {
        return Err(ViewerError::Recording {
            path: file.to_path_buf(),
            reason,
        });
    }
    Ok(rows)
}

fn flatten(a: &ArrayRef, values: &mut Vec<f64>, texts: &mut Vec<String>) {
    let any = a.as_any();
    if let Some(x) = any.downcast_ref::<Float32Array>() {
        values.extend(x.iter().flatten().map(f64::from));
    } else if let Some(x) = any.downcast_ref::<Float64Array>() {
        values.extend(x.iter().flatten());
    } else if let Some(x) = any.downcast_ref::<UInt32Array>() {
        values.extend(x.iter().flatten().map(f64::from));
    } else if let Some(x) = any.downcast_ref::<UInt8Array>() {
        values.extend(x.iter().flatten().map(f64::from));
    } else if let Some(x) = any.downcast_ref::<Int64Array>() {
        values.extend(x.iter().flatten().map(|v| v as f64));
    } else if let Some(x) = any.downcast_ref::<StringArray>() {
        texts.extend(x.iter().flatten().map(str::to_string));
    } else if let Some(x) = any.downcast_ref::<FixedSizeListArray>() {
        for i in 0..x.len() {
            flatten(&x.value(i), values, texts);
        }
    } else if let Some(x) = any.downcast_ref::<ListArray>() {
        for i in 0..x.len() {
            flatten(&x.value(i), values, texts);
        }
    } else if let Some(x) = any.downcast_ref::<StructArray>() {
        for c in x.columns() {
            flatten(c, values, texts);
        }
    }
}
