; TF5200 diagnosis, ID 21024 "Circle centre point and radius are not permitted at the same time.": the corrected example (N50 a full circle by I J)
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/253243787.html
; adapted: the "%err_21024.kor" file-name line dropped.
; expect: end X=400 Y=0 Z=0
; expect: blocks N10 N20 N30 N40 N50 N60 N99
N10 G00 X0 Y0 Z0 G17
N20 G01 X10 Y100 F10000
N30 X100Y200
N40 X200
N50 G02 X200 I50 J50
N60 G01 X400 Y0
N99 M30
