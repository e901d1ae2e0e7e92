"""The parts of a run-up simulation, one module per concept.

==================  =========================================================================
``errors``          :class:`SimulationError`
``conditions``      operating conditions: speed ramp or table, torque drive, drive coupling
``frequencies``     natural frequencies of a run's system (step choice, default coupling)
``step``            internal step and output rate (:func:`choose_step`)
``decimation``      the anti-alias FIR of the output decimation
``run_setup``       model + conditions -> the kernel arrays of one run (:func:`prepare_run`)
``equilibrium``     static equilibrium at the start of a run (:func:`static_equilibrium`)
``tooth_forces``    static tooth force per mesh under a run's load (:func:`static_tooth_forces`)
``result``          :class:`RunUpResult` and its CF-annotated Dataset
``settings``        the ``[simulation]`` table -> checked run settings -> conditions
==================  =========================================================================

The driver :func:`gearvib.simulate.simulate` puts them together; ``gearvib.simulate`` also
re-exports every public name of these modules. Imports inside this package run down the table.
"""
