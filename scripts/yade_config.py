"""Print 'version;features;realBits' of a YADE build, read from its yade/config.py without booting
YADE (used by CMake at configure time). Features are de-duplicated and sorted, comma-separated."""
import runpy
import sys

config = runpy.run_path(sys.argv[1])
features = ",".join(sorted(set(f for f in config["features"] if f)))
print("%s;%s;%d" % (config["version"], features, config["highPrecisionBits"]), end="")
