"""Load guard of the binding.

The compiled part of yade_mpm mirrors YADE's binary layout (see doc/architecture.md). Another YADE
version, another feature set or another ``Real`` silently changes that layout, so importing
refuses, naming what differs, before the compiled module is loaded. After loading, a self-test
writes sentinel values through YADE's own accessors and reads them back at the mirrored offsets.
"""


class YadeAbiMismatch(ImportError):
    """The running YADE is not the one the binding was built for."""


def _normalised_features(features):
    return sorted(set(f for f in features if f))


def check_compatibility(config, buildinfo):
    """Raise YadeAbiMismatch if `config` (yade.config or a stand-in) differs from `buildinfo`."""
    problems = []
    if config.version != buildinfo.yade_version:
        problems.append("YADE version is %r, the binding was built for %r" % (config.version, buildinfo.yade_version))
    running = _normalised_features(config.features)
    built = _normalised_features(buildinfo.yade_features.split(","))
    if running != built:
        extra = sorted(set(running) - set(built))
        missing = sorted(set(built) - set(running))
        problems.append("YADE features differ (running has extra %s, lacks %s)" % (extra, missing))
    if int(config.highPrecisionBits) != int(buildinfo.real_bits):
        problems.append("YADE's Real has %s bits, the binding was built for %s bits (use yade-double)"
                        % (config.highPrecisionBits, buildinfo.real_bits))
    if problems:
        raise YadeAbiMismatch("yade_mpm cannot load into this YADE: " + "; ".join(problems)
                              + ". Rebuild yade_mpm against the running YADE (scripts/build.sh).")


def self_test(module, wrapper, omega):
    """Set sentinel values from Python and read them at the mirrored offsets; restore the scene."""
    engine = wrapper.MpmTwoPhaseEngine(label="mpm_abi_sentinel_label", dead=True)
    shape = wrapper.MpmSolidPoints(color=(0.125, 0.25, 0.375), wire=True)
    material = wrapper.MpmSoilMat(density=1234.5, label="mpm_abi_sentinel_material")
    saved_dt = omega.dt
    sentinel_dt = 3.0517578125e-05  # exactly representable, unlikely to be a user's value
    # An erased body leaves an empty slot in O.bodies, so the Body offsets are checked only on an
    # empty scene (the usual place of an import), which is cleared again afterwards.
    check_body = len(omega.bodies) == 0
    body = wrapper.Body(shape=shape, material=material)
    body.state.blockedDOFs = "xyZ"  # bits 1 + 2 + 32: read back at the mirrored State offset
    body_id = omega.bodies.append(body) if check_body else -1
    try:
        omega.dt = sentinel_dt
        got = module.readMirroredValues(engine, shape, material, body_id)
    finally:
        if check_body:
            omega.bodies.clear()
        omega.dt = saved_dt
    expected = {
        "dt": sentinel_dt, "iter": omega.iter, "time": omega.time,
        "label": "mpm_abi_sentinel_label", "dead": True,
        "color": (0.125, 0.25, 0.375), "wire": True,
        "density": 1234.5, "materialLabel": "mpm_abi_sentinel_material",
    }
    if check_body:
        expected.update(bodyId=body_id, bodyShapeIsShape=True, bodyMaterialIsMat=True, blockedDOFs=35)
    wrong = ["%s: set %r, read %r" % (k, v, got.get(k)) for k, v in expected.items() if got.get(k) != v]
    if wrong:
        raise YadeAbiMismatch("yade_mpm's self-test read wrong values at the mirrored YADE offsets ("
                              + "; ".join(wrong) + "): the running YADE is not laid out as the binding assumes.")
