"""One solve on several MPI ranks (``mpiexec -n N vpcontact run``): the ranks of a run (:mod:`.ranks`), the mesh's
nodes shared among them (:mod:`.partition`) and the exchange of the values next to a rank's nodes (:mod:`.dofs`)."""
