"""Read what MpmHdf5Recorder wrote, as numpy arrays (no YADE needed)."""
from dataclasses import dataclass, field

import h5py
import numpy as np


@dataclass
class Record:
    iteration: int
    time: float  # [s]
    sets: dict = field(default_factory=dict)  # "solid_<id>" / "water_<id>" → {field name: array}
    grid: dict = field(default_factory=dict)  # node fields shaped (nz, ny, nx[, components]), plus
    #                                           "origin" (x, y, z) [m] and "spacing" [m]


def read(path):
    """All records of an MpmHdf5Recorder file, in the order written. Stresses come as (N, 3, 3)."""
    records = []
    with h5py.File(path, "r") as f:
        index = 0
        while "record_%d" % index in f:
            group = f["record_%d" % index]
            record = Record(int(group.attrs["iteration"]), float(group.attrs["time"]))
            for name, sub in group.items():
                if name == "grid":
                    nodes = [int(sub.attrs["nodes_%s" % a]) for a in "xyz"]
                    for key, data in sub.items():
                        values = np.asarray(data)
                        record.grid[key] = values.reshape(nodes[::-1] + list(values.shape[1:]))
                    record.grid["origin"] = np.array([sub.attrs["origin_%s" % a] for a in "xyz"])
                    record.grid["spacing"] = float(sub.attrs["spacing"])
                else:
                    arrays = {key: np.asarray(data) for key, data in sub.items()}
                    if "stress" in arrays:
                        arrays["stress"] = arrays["stress"].reshape(-1, 3, 3)
                    record.sets[name] = arrays
            records.append(record)
            index += 1
    return records
