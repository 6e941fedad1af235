"""MuJoCo sensors the recipe has a type for: a gyro and an accelerometer on one site are the
recipe's ``imu`` sensor on that site's frame (its noise kept, a cutoff on the ledger); the
rebuilt MJCF names them ``<imu>_gyro`` and ``<imu>_accel`` on a site ``<imu>_site``, which the
ledger says.  Every other sensor is on the ledger (:func:`robotkit.importer.mjcf.extras.ledger_rest`)."""

from __future__ import annotations

from robotkit.importer.mjcf.sites import free_name, site_origin
from robotkit.importer.names import valid_frame_name

GYRO, ACCELEROMETER, SITE = 3, 1, 6
"""MuJoCo's numbers for the gyro and accelerometer sensor types (mjtSensor) and for a site (mjtObj)."""


def add_imus(src, tree, recipe: dict, ledger) -> None:
    """The recipe's ``sensors:`` of the IMUs (``tree.sites`` and ``tree.kept_sensors`` filled)."""
    m, specs = src.model, list(src.spec.sensors)
    by_site: dict[int, dict[int, int]] = {}  # site -> {sensor type: sensor id}
    for i in range(m.nsensor):
        if int(m.sensor_objtype[i]) == SITE and int(m.sensor_type[i]) in (GYRO, ACCELEROMETER):
            by_site.setdefault(int(m.sensor_objid[i]), {}).setdefault(int(m.sensor_type[i]), i)
    sensors: dict = {}
    for s, found in sorted(by_site.items()):
        b = int(m.site_bodyid[s])
        if set(found) != {GYRO, ACCELEROMETER} or b not in tree.link_of:
            continue
        site = m.site(s).name
        name = free_name(tree, site if valid_frame_name(site) and "/" not in site else f"imu{s}")
        sensor = {"type": "imu", "parent": tree.link_of[b], "frame": name}
        o = site_origin(m, tree, s)
        if o:
            sensor["origin"] = o
        noise = {"gyro_noise": float(m.sensor_noise[found[GYRO]]),
                 "accel_noise": float(m.sensor_noise[found[ACCELEROMETER]])}
        if any(noise.values()):
            sensor["imu"] = {k: v for k, v in noise.items() if v}
        sensors[name] = sensor
        tree.links[name] = {}  # held while naming the others; the sensor makes this link
        tree.sites[s] = name
        for kind, suffix in ((GYRO, "gyro"), (ACCELEROMETER, "accel")):
            i = found[kind]
            tree.kept_sensors.add(i)
            where = src.where(specs[i]) if i < len(specs) else src.where()
            ledger.add(where, f"sensor '{m.sensor(i).name}' ({suffix})", "mjcf",
                       f"the recipe's imu sensor '{name}': written as '{name}_{suffix}' on site '{name}_site'")
            if float(m.sensor_cutoff[i]):
                ledger.add(where, f"sensor '{m.sensor(i).name}' ({suffix})", "all",
                           f"cutoff {float(m.sensor_cutoff[i]):g} dropped: the recipe's imu sensor has no cutoff")
    for name in sensors:
        del tree.links[name]
    if sensors:
        recipe["sensors"] = sensors
