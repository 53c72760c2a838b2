"""samp from Python: shape models, fitting sequences, training (docs/python.md).

    import samp
    model = samp.ShapeModel.load("models/samp_cars_r5.vdb")
    result = samp.fit_sequence("path/to/sequence", model)
    result.write("out")            # the files of `samp fit --out out`

The distributed batch driver is `python3 -m samp.batch` (docs/cluster.md).
"""

from ._samp import Error
from .api import FitResult, ShapeModel, Track, fit_sequence, sdf_of_mesh, train
from .options import FitOptions, RunFitOptions, SequenceOptions, TrainOptions

__all__ = [
    "Error", "ShapeModel", "FitResult", "Track", "fit_sequence", "train", "sdf_of_mesh",
    "RunFitOptions", "FitOptions", "SequenceOptions", "TrainOptions",
]
