; TF5200 programming manual, "Programming examples": summary of previous commands described
; https://infosys.beckhoff.com/content/1033/tf5200_programming_manual/206033419.html
; expect: end X=200 Y=200 Z=200
; expect: runs N50 2
% 100
N10 G00 X100 Y100           ;Move at rapid traverse to X=Y=100
N20 Z100;                    ;Move at rapid traverse to Z=100 G00
                            ;remains active until deselected by
                            ;another G function occurs
N30 G1 Z50 F5000 S1000 M3   ;Clockwise spindle rotation 1000 rpm and
                            ;Move linearly at feedrate
                            ;5000 mm/min) to Z=5
N40 Z100;                    ;Move at feedrate to Z=100
N50 G0 X200 Y200 Z200       ;Move at rapid traverse to X=Y=Z=200
N50 M5                      ;Spindle stop
N60 M30                     ;Program end
