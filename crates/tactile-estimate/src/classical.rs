//! Classical baselines from linfa, side by side with the burn MLPs: PCA
//! features, ridge regression, k-nearest-neighbour regression and Gaussian
//! naive Bayes (paper A's Bayes baseline). Inputs are standardised with
//! training statistics; angle targets go through their sin/cos encoding.

use crate::{Error, Result};
use linfa::prelude::*;
use linfa_bayes::GaussianNb;
use linfa_elasticnet::ElasticNet;
use linfa_nn::distance::L2Dist;
use linfa_nn::{CommonNearestNeighbour, NearestNeighbour};
use linfa_reduction::Pca;
use ndarray016::{Array1, Array2};

use crate::target::Target;

fn lerr(what: &str, e: impl std::fmt::Display) -> Error {
    Error::Linfa {
        what: what.into(),
        message: e.to_string(),
    }
}

fn array(x: &[Vec<f32>]) -> Result<Array2<f64>> {
    let k = x.first().map_or(0, Vec::len);
    Array2::from_shape_vec(
        (x.len(), k),
        x.iter().flatten().map(|&v| v as f64).collect(),
    )
    .map_err(|e| lerr("feature matrix", e))
}

/// Standardise `x` (and the others) with the statistics of `x`.
fn standardise(x: &Array2<f64>, others: &[&Array2<f64>]) -> (Array2<f64>, Vec<Array2<f64>>) {
    let mean = x
        .mean_axis(ndarray016::Axis(0))
        .unwrap_or_else(|| Array1::zeros(x.ncols()));
    let std = Array1::from(tactile_core::metrics::safe_scales(
        x.std_axis(ndarray016::Axis(0), 0.0).iter().copied(),
    ));
    let f = |a: &Array2<f64>| (a - &mean) / &std;
    (f(x), others.iter().map(|o| f(o)).collect())
}

/// PCA with `k` components fitted on `train`, applied to every set.
/// Fewer training vectors than components is [`Error::TooFewSamples`]
/// (linfa would refuse it in terms of matrix rows and columns).
pub fn pca(train: &[Vec<f32>], sets: &[&[Vec<f32>]], k: usize) -> Result<Vec<Vec<Vec<f32>>>> {
    if train.len() < k {
        return Err(Error::TooFewSamples(format!(
            "PCA with {k} components needs at least {k} training frames, got {}",
            train.len()
        )));
    }
    let tr = array(train)?;
    let model = Pca::params(k)
        .fit(&DatasetBase::from(tr))
        .map_err(|e| lerr("PCA", e))?;
    sets.iter()
        .map(|s| {
            let p: Array2<f64> = model.predict(&array(s)?);
            Ok(p.outer_iter()
                .map(|r| r.iter().map(|&v| v as f32).collect())
                .collect())
        })
        .collect()
}

/// Encoded target columns of label rows.
fn encoded(targets: &[Target], y: &[Vec<f64>]) -> Array2<f64> {
    let rows: Vec<Vec<f64>> = y
        .iter()
        .map(|r| {
            targets
                .iter()
                .zip(r)
                .flat_map(|(t, v)| t.encode(*v))
                .collect()
        })
        .collect();
    let k = rows.first().map_or(0, Vec::len);
    Array2::from_shape_vec((rows.len(), k), rows.into_iter().flatten().collect())
        .unwrap_or_else(|_| Array2::zeros((0, k)))
}

fn decode(targets: &[Target], cols: &Array2<f64>) -> Vec<Vec<f64>> {
    cols.outer_iter()
        .map(|r| {
            let r = r.to_vec();
            let mut at = 0;
            targets
                .iter()
                .map(|t| {
                    let v = t.decode(&r[at..at + t.width()]);
                    at += t.width();
                    v
                })
                .collect()
        })
        .collect()
}

/// Ridge regression (linfa's elastic net with no L1 part), one model per
/// encoded column.
pub fn ridge(
    targets: &[Target],
    (x, y): (&[Vec<f32>], &[Vec<f64>]),
    test: &[Vec<f32>],
    penalty: f64,
) -> Result<Vec<Vec<f64>>> {
    let (xs, t) = standardise(&array(x)?, &[&array(test)?]);
    let ys = encoded(targets, y);
    let mut out = Array2::<f64>::zeros((test.len(), ys.ncols()));
    for (j, col) in ys.columns().into_iter().enumerate() {
        let ds = Dataset::new(xs.clone(), col.to_owned());
        let model = ElasticNet::ridge()
            .penalty(penalty)
            .fit(&ds)
            .map_err(|e| lerr("ridge regression", e))?;
        let p: Array1<f64> = model.predict(&t[0]);
        out.column_mut(j).assign(&p);
    }
    Ok(decode(targets, &out))
}

/// k-nearest-neighbour regression: the mean encoded target of the `k`
/// nearest training vectors (linfa-nn's index, Euclidean on standardised
/// inputs).
pub fn knn(
    targets: &[Target],
    (x, y): (&[Vec<f32>], &[Vec<f64>]),
    test: &[Vec<f32>],
    k: usize,
) -> Result<Vec<Vec<f64>>> {
    let (xs, t) = standardise(&array(x)?, &[&array(test)?]);
    let ys = encoded(targets, y);
    let algo = if xs.ncols() <= 32 {
        CommonNearestNeighbour::KdTree
    } else {
        CommonNearestNeighbour::BallTree
    };
    let index = algo
        .from_batch(&xs, L2Dist)
        .map_err(|e| lerr("nearest-neighbour index", e))?;
    let mut out = Array2::<f64>::zeros((test.len(), ys.ncols()));
    for (i, p) in t[0].outer_iter().enumerate() {
        let near = index
            .k_nearest(p, k)
            .map_err(|e| lerr("nearest neighbours", e))?;
        let n = near.len().max(1) as f64;
        for (_, j) in near {
            let mut row = out.row_mut(i);
            row += &(&ys.row(j) / n);
        }
    }
    Ok(decode(targets, &out))
}

/// k-nearest-neighbour classification: the majority class of the `k`
/// nearest training vectors (ties go to the nearest of the tied classes).
pub fn knn_classify(
    x: &[Vec<f32>],
    y: &[usize],
    test: &[Vec<f32>],
    k: usize,
) -> Result<Vec<usize>> {
    let (xs, t) = standardise(&array(x)?, &[&array(test)?]);
    let algo = if xs.ncols() <= 32 {
        CommonNearestNeighbour::KdTree
    } else {
        CommonNearestNeighbour::BallTree
    };
    let index = algo
        .from_batch(&xs, L2Dist)
        .map_err(|e| lerr("nearest-neighbour index", e))?;
    let classes = y.iter().copied().max().map_or(0, |m| m + 1);
    t[0].outer_iter()
        .map(|p| {
            let near = index
                .k_nearest(p, k)
                .map_err(|e| lerr("nearest neighbours", e))?;
            let mut votes = vec![0usize; classes];
            for (_, j) in &near {
                votes[y[*j]] += 1;
            }
            let top = votes.iter().copied().max().unwrap_or(0);
            Ok(near
                .iter()
                .map(|(_, j)| y[*j])
                .find(|c| votes[*c] == top)
                .unwrap_or(0))
        })
        .collect()
}

/// Gaussian naive Bayes classes for `test`.
pub fn gaussian_nb(x: &[Vec<f32>], y: &[usize], test: &[Vec<f32>]) -> Result<Vec<usize>> {
    let ds = Dataset::new(array(x)?, Array1::from(y.to_vec()));
    let model = GaussianNb::params()
        .fit(&ds)
        .map_err(|e| lerr("Gaussian naive Bayes", e))?;
    let p: Array1<usize> = model.predict(&array(test)?);
    Ok(p.to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(n: usize, off: usize) -> (Vec<Vec<f32>>, Vec<Vec<f64>>) {
        (0..n)
            .map(|i| {
                let k = (i + off) as f64;
                let x = [(k * 0.37).sin(), (k * 0.11).cos(), (k * 0.53).sin()];
                (
                    x.iter().map(|&v| v as f32).collect(),
                    vec![3.0 * x[0] - x[1] + 0.5],
                )
            })
            .unzip()
    }

    #[test]
    fn ridge_knn_pca_and_bayes_work_on_easy_data() {
        let t = [Target::linear("y")];
        let (x, y) = data(300, 0);
        let (tx, ty) = data(50, 999);
        let truth: Vec<f64> = ty.iter().map(|r| r[0]).collect();
        let r: Vec<f64> = ridge(&t, (&x, &y), &tx, 1e-4)
            .unwrap()
            .iter()
            .map(|r| r[0])
            .collect();
        assert!(t[0].mae(&r, &truth) < 0.01);
        let k: Vec<f64> = knn(&t, (&x, &y), &tx, 3)
            .unwrap()
            .iter()
            .map(|r| r[0])
            .collect();
        assert!(t[0].mae(&k, &truth) < 0.3);
        let p = pca(&x, &[&x, &tx], 2).unwrap();
        assert_eq!((p[0].len(), p[0][0].len(), p[1].len()), (300, 2, 50));
        let cls: Vec<usize> = y.iter().map(|r| usize::from(r[0] > 0.5)).collect();
        let tcls: Vec<usize> = ty.iter().map(|r| usize::from(r[0] > 0.5)).collect();
        let pred = gaussian_nb(&x, &cls, &tx).unwrap();
        let acc = pred.iter().zip(&tcls).filter(|(a, b)| a == b).count();
        assert!(acc > 40, "{acc}/50");
        let pred = knn_classify(&x, &cls, &tx, 5).unwrap();
        let acc = pred.iter().zip(&tcls).filter(|(a, b)| a == b).count();
        assert!(acc > 40, "{acc}/50");
    }
}
