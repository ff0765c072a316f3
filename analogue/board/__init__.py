"""A board you can build (issue 13): the stick-slip model as an op-amp analogue computer with
real parts, E-series values, a seeded noise chain, tolerance Monte Carlo, calibration,
schematic and bill of materials.  Modules: ``opamp`` (macromodel), ``design`` (scaling and
rounding), ``friction`` (bridge with active current sources; OTA alternative),
``noise_chain`` (seeded DAC sequence, Bessel, AC coupling), ``netlist`` (the deck),
``runner`` (ngspice runs), ``tolerance`` (Monte Carlo), ``calibration``, ``schematic``,
``bom``, ``report``."""
