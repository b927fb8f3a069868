//! Dormand-Prince 8(5,3) (Hairer's DOP853): eighth order with the combined fifth- and
//! third-order error estimate. Steps are shortened to end exactly on each output time, so the
//! outputs carry the full eighth-order accuracy without an interpolant.
//!
//! Coefficients: Hairer, Nørsett & Wanner, "Solving Ordinary Differential Equations I", the
//! published DOP853 tableau.

use super::{Project, Reason, States, Rhs, RunError, Settings, Solution, Stats, combine, finite, initial_step};

const C: [f64; 12] = [
    0.0,
    0.526001519587677318785587544488e-01,
    0.789002279381515978178381316732e-01,
    0.118350341907227396726757197510e+00,
    0.281649658092772603273242802490e+00,
    0.333333333333333333333333333333e+00,
    0.25e+00,
    0.307692307692307692307692307692e+00,
    0.651282051282051282051282051282e+00,
    0.6e+00,
    0.857142857142857142857142857142e+00,
    1.0,
];

/// Stage weights, row `i` for stage `i` (zero entries omitted by the tableau are zero here).
const A: [[f64; 11]; 12] = [
    [0.0; 11],
    [5.26001519587677318785587544488e-2, 0., 0., 0., 0., 0., 0., 0., 0., 0., 0.],
    [1.97250569845378994544595329183e-2, 5.91751709536136983633785987549e-2, 0., 0., 0., 0., 0., 0., 0., 0., 0.],
    [2.95875854768068491816892993775e-2, 0., 8.87627564304205475450678981324e-2, 0., 0., 0., 0., 0., 0., 0., 0.],
    [2.41365134159266685502369798665e-1, 0., -8.84549479328286085344864962717e-1, 9.24834003261792003115737966543e-1, 0., 0., 0., 0., 0., 0., 0.],
    [3.7037037037037037037037037037e-2, 0., 0., 1.70828608729473871279604482173e-1, 1.25467687566822425016691814123e-1, 0., 0., 0., 0., 0., 0.],
    [3.7109375e-2, 0., 0., 1.70252211019544039314978060272e-1, 6.02165389804559606850219397283e-2, -1.7578125e-2, 0., 0., 0., 0., 0.],
    [
        3.70920001185047927108779319836e-2,
        0.,
        0.,
        1.70383925712239993810214054705e-1,
        1.07262030446373284651809199168e-1,
        -1.53194377486244017527936158236e-2,
        8.27378916381402288758473766002e-3,
        0.,
        0.,
        0.,
        0.,
    ],
    [
        6.24110958716075717114429577812e-1,
        0.,
        0.,
        -3.36089262944694129406857109825e0,
        -8.68219346841726006818189891453e-1,
        2.75920996994467083049415600797e1,
        2.01540675504778934086186788979e1,
        -4.34898841810699588477366255144e1,
        0.,
        0.,
        0.,
    ],
    [
        4.77662536438264365890433908527e-1,
        0.,
        0.,
        -2.48811461997166764192642586468e0,
        -5.90290826836842996371446475743e-1,
        2.12300514481811942347288949897e1,
        1.52792336328824235832596922938e1,
        -3.32882109689848629194453265587e1,
        -2.03312017085086261358222928593e-2,
        0.,
        0.,
    ],
    [
        -9.3714243008598732571704021658e-1,
        0.,
        0.,
        5.18637242884406370830023853209e0,
        1.09143734899672957818500254654e0,
        -8.14978701074692612513997267357e0,
        -1.85200656599969598641566180701e1,
        2.27394870993505042818970056734e1,
        2.49360555267965238987089396762e0,
        -3.0467644718982195003823669022e0,
        0.,
    ],
    [
        2.27331014751653820792359768449e0,
        0.,
        0.,
        -1.05344954667372501984066689879e1,
        -2.00087205822486249909675718444e0,
        -1.79589318631187989172765950534e1,
        2.79488845294199600508499808837e1,
        -2.85899827713502369474065508674e0,
        -8.87285693353062954433549289258e0,
        1.23605671757943030647266201528e1,
        6.43392746015763530355970484046e-1,
    ],
];

const B: [f64; 12] = [
    5.42937341165687622380535766363e-2,
    0.,
    0.,
    0.,
    0.,
    4.45031289275240888144113950566e0,
    1.89151789931450038304281599044e0,
    -5.8012039600105847814672114227e0,
    3.1116436695781989440891606237e-1,
    -1.52160949662516078556178806805e-1,
    2.01365400804030348374776537501e-1,
    4.47106157277725905176885569043e-2,
];

/// Third-order embedded weights on stages 1, 9, 12.
const BHH: [f64; 3] = [0.244094488188976377952755905512e+00, 0.733846688281611857341361741547e+00, 0.220588235294117647058823529412e-01];

/// Fifth-order error weights.
const ER: [f64; 12] = [
    0.1312004499419488073250102996e-01,
    0.,
    0.,
    0.,
    0.,
    -0.1225156446376204440720569753e+01,
    -0.4957589496572501915214079952e+00,
    0.1664377182454986536961530415e+01,
    -0.3503288487499736816886487290e+00,
    0.3341791187130174790297318841e+00,
    0.8192320648511571246570742613e-01,
    -0.2235530786388629525884427845e-01,
];

pub(super) fn run(f: &mut Rhs, project: &mut Project, y0: &[f64], outputs: &[f64], s: &Settings) -> Result<Solution, RunError> {
    let n = y0.len();
    let mut stats = Stats::default();
    let mut t = outputs[0];
    let mut y = y0.to_vec();
    let mut states = States::new(n, outputs.len());
    states.push(&y);
    let mut next = 1;
    let stop = |t: f64, y: &[f64], reason: Reason| RunError { t, state: y.to_vec(), reason };
    let mut k: Vec<Vec<f64>> = vec![vec![0.0; n]; 12];
    f(t, &y, &mut k[0], &mut stats).map_err(|r| stop(t, &y, r))?;
    let mut h = initial_step(f, t, &y, &k[0].clone(), 8, s, &mut stats).map_err(|r| stop(t, &y, r))?;
    let (safe, facc1, facc2, expo1) = (0.9, 1.0 / 0.333, 1.0 / 6.0, 1.0 / 8.0);
    let mut rejected_last = false;
    let (mut tmp, mut y_new) = (vec![0.0; n], vec![0.0; n]);
    while next < outputs.len() {
        if stats.steps + stats.rejected >= s.max_steps {
            return Err(stop(t, &y, Reason::TooManySteps(s.max_steps)));
        }
        if 0.1 * h.abs() <= t.abs().max(1.0) * f64::EPSILON {
            return Err(stop(t, &y, Reason::StepSizeTooSmall { h }));
        }
        let target = outputs[next];
        let landing = t + 1.01 * h >= target;
        let step = if landing { target - t } else { h };
        for st in 1..12 {
            combine(&mut tmp, &y, step, &A[st][..st], &k);
            let (_, tail) = k.split_at_mut(st);
            f(t + C[st] * step, &tmp, &mut tail[0], &mut stats).map_err(|r| stop(t, &y, r))?;
        }
        let (mut err5, mut err3) = (0.0, 0.0);
        for i in 0..n {
            let mut acc = 0.0;
            for j in 0..12 {
                acc += B[j] * k[j][i];
            }
            y_new[i] = y[i] + step * acc;
            let sk = s.atol + s.rtol * y[i].abs().max(y_new[i].abs());
            let e3 = acc - BHH[0] * k[0][i] - BHH[1] * k[8][i] - BHH[2] * k[11][i];
            let mut e5 = 0.0;
            for j in 0..12 {
                e5 += ER[j] * k[j][i];
            }
            err5 += (e5 / sk) * (e5 / sk);
            err3 += (e3 / sk) * (e3 / sk);
        }
        let mut deno = err5 + 0.01 * err3;
        if deno <= 0.0 {
            deno = 1.0;
        }
        let e = step.abs() * err5 * (1.0 / (n as f64 * deno)).sqrt();
        if !e.is_finite() {
            stats.rejected += 1;
            rejected_last = true;
            h = step * 0.2;
            continue;
        }
        let fac11 = e.powf(expo1);
        if e <= 1.0 {
            stats.steps += 1;
            let fac = (fac11 / safe).clamp(facc2, facc1);
            let mut h_new = step / fac;
            t = if landing { target } else { t + step };
            std::mem::swap(&mut y, &mut y_new);
            if !finite(&y) {
                return Err(stop(t, &y, Reason::Diverged));
            }
            project(t, &mut y).map_err(|r| stop(t, &y, r))?;
            f(t, &y, &mut tmp, &mut stats).map_err(|r| stop(t, &y, r))?;
            k[0].copy_from_slice(&tmp);
            if landing {
                states.push(&y);
                next += 1;
                // A step shortened to land says little about the next one.
                h_new = h_new.max(h);
            }
            h_new = h_new.min(s.h_max);
            if rejected_last {
                h_new = h_new.min(step);
            }
            rejected_last = false;
            h = h_new;
        } else {
            stats.rejected += 1;
            rejected_last = true;
            h = step / (fac11 / safe).min(facc1);
        }
    }
    Ok(Solution { times: outputs.to_vec(), states, stats })
}
