; TF5200 programming manual, "Spindle-specific movement (M3, M4, M5)": one spindle S
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/208191499.html
N10 S[REV1000]     (Speed 1000 rpm is stored,)
                   (no spindle rotation because M05 is default)
N20 S[M03]         (Spindle rotation cw at 1000 rpm)
N30 S[M04]         (Spindle rotation ccw at 1000 rpm)
N40 S[REV500]      (Spindle rotation ccw at 500 rpm)
N50 S[M05 REV300]  (Spindle stop, speed 300 rpm is stored)
N60 S[M04]         (Spindle rotation ccw at 300 rpm)
N70 S[M05]         (Spindle stop)
N80 S[M03 REV1000] (Spindle rotation cw at 1000 rpm)
N90 M30                (Program end)
