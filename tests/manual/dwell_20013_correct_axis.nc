; TF5200 diagnosis, ID 20013 "Dwell time is programmed directly and via coordinate.": the correct program (dwell time with axis information)
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/250532491.html
; expect: dwell N20 2 s
%dec0013A2.sol
N10 G00 X0 Y0 Z0
N20 G04 X2
N1000 M30
