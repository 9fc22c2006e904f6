"""The gear-pair dynamics on the tables: native solver, reference, sweeps, harmonics."""
