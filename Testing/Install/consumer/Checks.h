// The checks a consumer program runs; each returns the number of failed comparisons and prints what it
// compared. Every expected value is computed here from the law or the set-up, not taken from CementSPH.
#pragma once

int checkSph();       // SphCheck.cpp: kernel normalisation and derivative
int checkImagingIO(); // ImagingIOCheck.cpp: NRRD round trip of an analytic volume
int checkCTScene();   // CTSceneCheck.cpp: porous solid of a two-slab CT, counted by hand
int checkDrr();       // DrrCheck.cpp: DRR of a uniform block = mu * length
int checkCaseFarm();  // CaseFarmCheck.cpp: the serial case farm sums 0^2 + ... + 9^2

// Prints "name: got (expected), ok|FAILED" and returns 0 when |got - expected| <= tolerance.
int compare(const char* name, double got, double expected, double tolerance);
