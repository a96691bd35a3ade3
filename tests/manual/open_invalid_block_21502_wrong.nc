; TF5200 diagnosis, ID 21502 "There are pending invalid control blocks at global subroutine end.": the wrong program
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/254949771.html
; adapted: a main program calls the page's subroutine (file glob_sub.nc).
; expect: error 21502
N010 L glob_sub.nc
N1000 M30
; --- file glob_sub.nc
% glob_sub
N10 G00 X0 Y0 Z0
N20 P1=0
N30 $IF P1 == 1
N40 Y100
N100 X100
N150 M29
