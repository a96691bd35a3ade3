; TF5200 diagnosis, ID 21024 "Circle centre point and radius are not permitted at the same time.": the example with error
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/253243787.html
; adapted: the "%err_21024.err" file-name line dropped.
; expect: error 21024
N10 G00 X0 Y0 Z0 G17
N20 G01 X10 Y100 F10000
N30 X100Y200
N40 X200
N50 G02 X200 I50 J50 R50
N60 G01 X400 Y0
N99 M30
