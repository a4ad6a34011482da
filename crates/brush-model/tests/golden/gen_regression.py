"""Golden values for brush-model's regression, computed independently with statsmodels.

Needs: numpy, statsmodels (pip install numpy statsmodels).
Run from this folder:  python3 gen_regression.py > regression.json
The Rust test `tests/golden.rs` fits the same rows and compares every figure.
"""
import json

import numpy as np
import statsmodels.api as sm

rng = np.random.default_rng(20261123)
rows = []
for h in (11.0, 13.0, 15.0, 17.0, 20.0):
    for a_deg in (0.0, 5.0, 10.0):
        b_deg = float(rng.choice([0.0, 5.0]))
        a, b = np.radians(a_deg), np.radians(b_deg)
        lt = 0.9 * h + 12.0 * a + 3.0 * b + 0.4 + rng.normal(0, 0.3)
        lh = 0.35 * h + 3.0 * a - 1.0 * b + 0.2 + rng.normal(0, 0.15)
        lr = 0.2 * h + 0.6 * a + 0.5 * b + rng.normal(0, 0.08)
        rows.append([h, a_deg, b_deg, round(lt, 4), round(lh, 4), round(lr, 4)])

data = np.array(rows)
X = sm.add_constant(np.column_stack([data[:, 0], np.radians(data[:, 1]), np.radians(data[:, 2])]))
names = ["intercept", "h_mm", "alpha_rad", "beta_rad"]


def report(y, exog):
    r = sm.OLS(y, exog).fit()
    return {
        "coef": dict(zip(names, r.params.tolist())),
        "std_err": dict(zip(names, r.bse.tolist())),
        "t": dict(zip(names, r.tvalues.tolist())),
        "r2": r.rsquared,
        "adj_r2": r.rsquared_adj,
        "resid_se": float(np.sqrt(r.scale)),
    }


general = {k: report(data[:, i], X) for k, i in (("lt_mm", 3), ("lh_mm", 4), ("lr_mm", 5))}
cond = sm.OLS(data[:, 3], X).fit().condition_number
paper = {"sum_mm": report(data[:, 3] + data[:, 4], X)}
k4 = sm.OLS(data[:, 4], data[:, 3]).fit()
k5 = sm.OLS(data[:, 5], data[:, 3]).fit()
out = {
    "header": "h_mm,alpha_deg,beta_deg,lt_mm,lh_mm,lr_mm",
    "rows": rows,
    "condition_number": cond,
    "general": general,
    "paper": paper,
    "k4": float(k4.params[0]),
    "k4_std_err": float(k4.bse[0]),
    "k5": float(k5.params[0]),
    "k5_std_err": float(k5.bse[0]),
}
print(json.dumps(out, indent=1))
