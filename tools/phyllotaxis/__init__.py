"""phyllotaxis: Place florets by Ridley phyllotaxis (thesis ch. 5): scene.scn and, when dynamic, rba/NNNN.rba."""
