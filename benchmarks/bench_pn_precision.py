"""Work–precision of the coupled post-Newtonian system: pnrotor's DOP853 at atol 1e-6 … 1e-14 against
LALSuite's SpinTaylorT4 and scipy's solve_ivp, the study of :mod:`pnrotor.pn_study` (its docstring has the
cases, the reference and the measures; ``pnrotor bench --pn`` runs the same).

    python benchmarks/bench_pn_precision.py [--rounds 7] [--quick] [--cases …] [--no-scipy] [--no-lal]
                                            [--json out.json] [--figure diagram.png]
"""

from pnrotor.pn_study import main

if __name__ == "__main__":
    main()
