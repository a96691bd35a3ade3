; TF5200 programming manual, "M/H functions with optional additional information": block N80, M functions with additional values on X, Y, the spindle and the channel
; https://infosys.beckhoff.com/content/1033/tccncprogramming/15556839051.html
; adapted: block N80 alone, M30 appended; the fixture channel list declares M52 M54 M63.
; expect: blocks N80 N90
N80 X[M52=-345 M54=567] Y[M63=-789] S[M05 M63=789 M54=-567] M54 M63
N90 M30
