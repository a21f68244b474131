//! Bindings of `dream_core::neighbours`: range and field-of-view queries as CSR arrays.

use dream_core::neighbours::{self as core, FieldOfView, RowsOf};
use dream_core::perceive::{linked as core_linked, perceive as core_perceive, Perceived, Radio, Sight};
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::arrays::{columns_in, count_of, flags_of, indices_of, points_of, vector_in, vector_of, with_indices};
use crate::draws::{loss_of, LossArgs};
use crate::errors::{value_error, PyDreamResult};

type CsrArrays<'py> = (
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<f64>>,
);

/// Neighbours of every robot (or of those flagged in `rows`) within `radius` (and field of view)
/// as `(indptr, indices, distances)`.
#[pyfunction]
#[pyo3(signature = (positions, radius, headings=None, direction=0.0, fov=std::f64::consts::TAU, max_neighbours=None, rows=None))]
#[allow(clippy::too_many_arguments)]
pub fn neighbours<'py>(
    py: Python<'py>,
    positions: Bound<'py, PyAny>,
    radius: f64,
    headings: Option<Bound<'py, PyAny>>,
    direction: f64,
    fov: f64,
    max_neighbours: Option<i64>,
    rows: Option<Bound<'py, PyAny>>,
) -> PyDreamResult<CsrArrays<'py>> {
    let positions = columns_in::<2>("positions", &positions)?;
    let [xs, ys] = positions.get();
    let max_neighbours = max_neighbours.map(|k| count_of("max_neighbours", k)).transpose()?;
    let headings = headings
        .map(|h| vector_of("headings", &h, Some(xs.len())))
        .transpose()?;
    let rows = rows.map(|r| flags_of("rows", &r, xs.len())).transpose()?;
    let csr = py.detach(|| {
        let view = headings.as_deref().map(|headings| FieldOfView {
            headings,
            direction,
            fov,
        });
        core::within(xs, ys, radius, view, max_neighbours, rows.as_deref())
    })?;
    Ok((
        csr.indptr.into_pyarray(py),
        csr.indices.into_pyarray(py),
        csr.distances.into_pyarray(py),
    ))
}

/// Which `points` `(k, 2)` lie farther than `distance` from every one of `others` `(m, 2)` in the
/// same row (rows cut by the offsets; one row without them), as a bool array `(k,)`.
#[pyfunction]
#[pyo3(signature = (points, others, distance, points_offsets=None, others_offsets=None))]
pub fn far_from<'py>(
    py: Python<'py>,
    points: Bound<'py, PyAny>,
    others: Bound<'py, PyAny>,
    distance: f64,
    points_offsets: Option<Bound<'py, PyAny>>,
    others_offsets: Option<Bound<'py, PyAny>>,
) -> PyDreamResult<Bound<'py, PyArray1<bool>>> {
    let points = points_of::<2>("points", &points)?;
    let others = points_of::<2>("others", &others)?;
    let offsets = |arg: &str, given: Option<Bound<'py, PyAny>>, len: usize| match given {
        Some(offsets) => indices_of(arg, &offsets),
        None => Ok(vec![0, len as i64]),
    };
    let points_offsets = offsets("points_offsets", points_offsets, points.len())?;
    let others_offsets = offsets("others_offsets", others_offsets, others.len())?;
    let far = py.detach(|| {
        let rows = RowsOf {
            points: &points,
            points_offsets: &points_offsets,
            others: &others,
            others_offsets: &others_offsets,
        };
        core::far_from(rows, distance)
    })?;
    Ok(far.into_pyarray(py))
}

/// Who the robots `rows` see and hear: `(seen, heard)`, `(offsets, ids, distances, bearings, dx,
/// dy, *carried)` (each of `carried` `(n,)` read at the robots seen; bearings empty unless
/// `bearings`) and `(offsets, ids, distances, lost, *summed)` (each of `summed` `(n,)` added up
/// over each row heard, whose ids and distances are then left empty: none given, the rows are
/// only counted; `lost`, each row's messages lost to the radio's `loss` `(seed, stream, step,
/// keep, per_metre)`, empty without).
#[pyfunction]
#[pyo3(signature = (positions, headings, rows, *, sight=None, radio_range=None, talking=None, carried=None, bearings=true, summed=None, loss=None))]
#[allow(clippy::too_many_arguments)]
pub fn perceive<'py>(
    py: Python<'py>,
    positions: Bound<'py, PyAny>,
    headings: Bound<'py, PyAny>,
    rows: Bound<'py, PyAny>,
    sight: Option<(f64, f64, f64)>,
    radio_range: Option<f64>,
    talking: Option<Bound<'py, PyAny>>,
    carried: Option<Vec<Bound<'py, PyAny>>>,
    bearings: bool,
    summed: Option<Vec<Bound<'py, PyAny>>>,
    loss: Option<LossArgs>,
) -> PyDreamResult<(Bound<'py, PyTuple>, Bound<'py, PyTuple>)> {
    let positions = columns_in::<2>("positions", &positions)?;
    let [xs, ys] = positions.get();
    let n = xs.len();
    let headings = vector_in("headings", &headings, Some(n))?;
    let carried = carried.unwrap_or_default();
    let carried = carried
        .iter()
        .map(|column| vector_in("carried", column, Some(n)))
        .collect::<PyDreamResult<Vec<_>>>()?;
    let sums = summed.is_some();
    let summed = summed
        .unwrap_or_default()
        .iter()
        .map(|column| vector_in("summed", column, Some(n)))
        .collect::<PyDreamResult<Vec<_>>>()?;
    let summed: Vec<&[f64]> = summed.iter().map(|c| &c[..]).collect();
    let loss = loss_of(loss)?;
    let rows = indices_of("rows", &rows)?;
    let talking = talking.map(|t| flags_of("talking", &t, n)).transpose()?;
    let radio = match (radio_range, talking.as_deref()) {
        (Some(range), Some(talking)) => Some(Radio {
            range,
            talking,
            summed: sums.then_some(&summed[..]),
            loss,
        }),
        (None, None) if !sums && loss.is_none() => None,
        (None, None) => {
            return Err(value_error(
                "`summed` and `loss` need a radio: give `radio_range` and `talking`".into(),
            ))
        }
        _ => return Err(value_error("give both `radio_range` and `talking`, or neither".into())),
    };
    let sight = sight.map(|(range, fov, direction)| Sight {
        range,
        fov,
        direction,
        bearings,
    });
    let columns: Vec<&[f64]> = carried.iter().map(|c| &c[..]).collect();
    let headings: &[f64] = &headings;
    let (seen, heard) = py.detach(|| core_perceive(xs, ys, headings, &rows, sight, radio, &columns))?;
    let Perceived {
        offsets,
        ids,
        distances,
        bearings,
        dxs,
        dys,
        carried,
        ..
    } = seen;
    let mut items: Vec<Bound<'py, PyAny>> = vec![offsets.into_pyarray(py).into_any(), ids.into_pyarray(py).into_any()];
    items.extend([distances, bearings, dxs, dys].map(|column| column.into_pyarray(py).into_any()));
    items.extend(carried.into_iter().map(|column| column.into_pyarray(py).into_any()));
    let mut heard_items: Vec<Bound<'py, PyAny>> = vec![
        heard.offsets.into_pyarray(py).into_any(),
        heard.ids.into_pyarray(py).into_any(),
        heard.distances.into_pyarray(py).into_any(),
        heard.lost.into_pyarray(py).into_any(),
    ];
    heard_items.extend(
        heard
            .summed
            .into_iter()
            .map(|column| column.into_pyarray(py).into_any()),
    );
    Ok((PyTuple::new(py, items)?, PyTuple::new(py, heard_items)?))
}

/// What the robots `rows` (increasing ids) hear over the communication graph `(indptr, indices)`
/// among the `talking` robots: `(offsets, ids, distances)` over those rows, the distances NaN
/// without `positions`. The graph is read in place (a swarm's links are most of a step's
/// radio), not copied.
#[pyfunction]
#[pyo3(signature = (rows, indptr, indices, talking, positions=None))]
pub fn linked<'py>(
    py: Python<'py>,
    rows: Bound<'py, PyAny>,
    indptr: Bound<'py, PyAny>,
    indices: Bound<'py, PyAny>,
    talking: Bound<'py, PyAny>,
    positions: Option<Bound<'py, PyAny>>,
) -> PyDreamResult<CsrArrays<'py>> {
    let rows = indices_of("rows", &rows)?;
    let coordinates = positions.map(|p| columns_in::<2>("positions", &p)).transpose()?;
    let at = coordinates.as_ref().map(|columns| {
        let [xs, ys] = columns.get();
        (xs, ys)
    });
    let n = at.map_or(talking.len()?, |(xs, _)| xs.len());
    let talking = flags_of("talking", &talking, n)?;
    let heard = with_indices("indptr", &indptr, |indptr| {
        with_indices("indices", &indices, |indices| {
            Ok(py.detach(|| core_linked(at, (indptr, indices), &rows, &talking))?)
        })
    })?;
    Ok((
        heard.offsets.into_pyarray(py),
        heard.ids.into_pyarray(py),
        heard.distances.into_pyarray(py),
    ))
}
