"""
ANFIS as a scikit-learn estimator
=================================

MATLAB-style ``genfis`` + ``anfis`` hybrid learning (least squares for the consequents, gradient descent for the
membership functions) on a one-input toy problem.
"""

import matplotlib.pyplot as plt
import numpy as np

from toolpoint import ANFIS

X = np.linspace(0.0, 1.0, 40)[:, None]
y = np.sin(3 * X[:, 0])
fis = ANFIS(n_mfs=3, mf="gauss", epochs=50).fit(X, y)
xs = np.linspace(0, 1, 200)[:, None]
plt.plot(X[:, 0], y, "o", label="training data")
plt.plot(xs[:, 0], fis.predict(xs), label="ANFIS, 3 gauss MFs")
plt.xlabel("x")
plt.ylabel("y")
plt.legend()
plt.show()
